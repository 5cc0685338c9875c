"""Attacks on the viewer's server, played against a live server on 127.0.0.1.

Each test sends real requests over loopback sockets (bounded counts and times) the way a
third-party web page, a DNS-rebinding page or a careless local client would, and checks
that the server refuses them before any work: no bake starts (the server's own
``bake_queue.started`` counter and the viewer's in-memory table sets), and nothing is
written to the table cache folder, which points at an empty temporary folder for the whole
module and is checked after every test. The faults these tests guard against were found
by the same attacks on the earlier server: every API answer 200 with ``Host:
evil.example.com``; a cross-origin GET baking tables for 17 s and writing a 47 MB cache
entry; ``observer_altitude_m=nan`` refused only after a bake; 300 idle connections pinning
300 threads; a traceback for every client that hung up.
"""

from __future__ import annotations

import http.client
import json
import os
import re
import signal
import socket
import struct
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


# -- a live server with its own empty cache folder --------------------------------------------
@pytest.fixture(scope="module")
def cache_dir(tmp_path_factory):
    d = tmp_path_factory.mktemp("viewer-cache")
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("SKYDOME_CACHE_DIR", str(d))
        yield d


@pytest.fixture(scope="module")
def server(cache_dir):
    from skydome.viewer.server import make_server

    srv = make_server("127.0.0.1", 0)
    t = threading.Thread(target=srv.serve_forever, kwargs={"poll_interval": 0.05}, daemon=True)
    t.start()
    yield srv
    srv.shutdown()
    t.join()
    srv.server_close()


@pytest.fixture(autouse=True)
def nothing_written(cache_dir):
    """After every test: the cache folder is still empty (no entry, no temporary)."""
    yield
    left = sorted(p.relative_to(cache_dir).as_posix() for p in cache_dir.rglob("*"))
    assert left == [], f"written to the table cache: {left[:10]}"


def _port(srv) -> int:
    return srv.server_address[1]


def _request(srv, path: str, headers: dict[str, str] | None = None, host: str | None = "own",
             timeout: float = 20.0):
    """(status, headers, body) of one raw request; ``host``: "own" for the server's own
    ``127.0.0.1:PORT``, None for no Host header, else that value."""
    c = http.client.HTTPConnection("127.0.0.1", _port(srv), timeout=timeout)
    c.putrequest("GET", path, skip_host=True, skip_accept_encoding=True)
    if host == "own":
        c.putheader("Host", f"127.0.0.1:{_port(srv)}")
    elif host is not None:
        c.putheader("Host", host)
    for k, v in (headers or {}).items():
        c.putheader(k, v)
    c.endheaders()
    r = c.getresponse()
    body = r.read()
    c.close()
    return r.status, dict(r.getheaders()), body


def _token(srv) -> str:
    status, _, body = _request(srv, "/")
    m = re.search(rb'<meta name="skydome-token" content="([A-Za-z0-9_-]+)">', body)
    assert status == 200 and m
    return m.group(1).decode()


def _viewer_tables():
    """The viewer's in-memory table sets (what a bake adds)."""
    from skydome.viewer import scene

    return (set(scene._PRECOMPUTED_MODELS), set(scene._LUTS), set(scene._HILLAIRE_CACHE),
            set(scene._DOBASHI_CACHE))


BAKE = "/api/scene?model=precomputed&turbidity=3.3&sun_elevation=30"
API_PATHS = ["/api/models", BAKE, "/api/scene?model=hillaire2020&turbidity=4.1",
             "/api/scene?model=dobashi2002&turbidity=3", "/api/lut?key=x&name=y"]


def _assert_refused(srv, path, headers=None, host="own", status=403):
    before = (srv.bake_queue.started, _viewer_tables())
    st, h, body = _request(srv, path, headers, host)
    assert st == status, (path, headers, host, st, body[:200])
    assert srv.token.encode() not in body
    assert h["Content-Type"] == "application/json" and "error" in json.loads(body)
    assert (srv.bake_queue.started, _viewer_tables()) == before, "work done for a refused request"
    return json.loads(body)["error"]


# -- who may ask -------------------------------------------------------------------------------
FOREIGN_HOSTS = ["evil.example.com", "evil.example.com:{port}", "127.0.0.1", "127.0.0.1:1",
                 "localhost", "localhost.evil.example.com:{port}", "127.0.0.1:{port}.evil.com",
                 "127.0.0.2:{port}", "0.0.0.0:{port}", "[::ffff:127.0.0.1]:{port}", ""]


@pytest.mark.parametrize("host", FOREIGN_HOSTS)
def test_foreign_host_refused(server, host):
    """A DNS-rebinding page talks to 127.0.0.1 under its own name: every path is 403,
    the page itself included (its token must not reach another name)."""
    host = host.format(port=_port(server))
    tok = server.token
    for path in ["/", "/index.html", "/app.js", *API_PATHS]:
        err = _assert_refused(server, path, {"X-Skydome-Token": tok}, host=host)
        assert "is not served" in err


def test_missing_or_repeated_host_refused(server):
    own = f"127.0.0.1:{_port(server)}"
    assert "(none)" in _assert_refused(server, "/", host=None)
    c = http.client.HTTPConnection("127.0.0.1", _port(server), timeout=10)
    c.putrequest("GET", "/", skip_host=True, skip_accept_encoding=True)
    c.putheader("Host", own)
    c.putheader("Host", "evil.example.com")
    c.endheaders()
    r = c.getresponse()
    assert r.status == 403 and server.token.encode() not in r.read()
    c.close()


def test_own_hosts_served(server):
    port = _port(server)
    for host in (f"127.0.0.1:{port}", f"localhost:{port}", f"LocalHost:{port}", f"[::1]:{port}"):
        st, _, body = _request(server, "/", host=host)
        assert st == 200 and server.token.encode() in body, host


@pytest.mark.parametrize("origin", ["http://evil.example.com", "null", "https://127.0.0.1:{port}",
                                    "http://127.0.0.1:1", "http://localhost:{port}",
                                    "http://127.0.0.1:{port}.evil.com", ""])
def test_cross_origin_refused(server, origin):
    """The issue's attack: a cross-origin "simple" GET of a precomputed bake. Refused
    before any work, with or without the right token. (http://localhost:PORT is another
    origin than http://127.0.0.1:PORT, the Host this request gives.)"""
    origin = origin.format(port=_port(server))
    for path in ["/app.js", *API_PATHS]:
        for headers in ({"Origin": origin}, {"Origin": origin, "X-Skydome-Token": server.token}):
            assert "cross-origin" in _assert_refused(server, path, headers)


def test_own_origin_accepted(server):
    own = f"http://127.0.0.1:{_port(server)}"
    st, _, body = _request(server, "/api/models", {"Origin": own, "X-Skydome-Token": server.token,
                                                   "Sec-Fetch-Site": "same-origin"})
    assert st == 200 and "precomputed" in json.loads(body)


@pytest.mark.parametrize("site", ["cross-site", "same-site"])
def test_sec_fetch_site_refused(server, site):
    """Cross-site and same-site (another port of localhost is the same site) requests
    are refused, a subresource of the page included; only a top-level navigation to the
    page, which does no work and whose answer the other page cannot read, is served."""
    tok = server.token
    for path in API_PATHS:
        for mode in ({"Sec-Fetch-Mode": "no-cors", "Sec-Fetch-Dest": "image"},
                     {"Sec-Fetch-Mode": "cors", "Sec-Fetch-Dest": "empty"},
                     {"Sec-Fetch-Mode": "navigate", "Sec-Fetch-Dest": "document"}):
            err = _assert_refused(server, path, {"Sec-Fetch-Site": site, "X-Skydome-Token": tok,
                                                 **mode})
            assert "cross-site" in err
    for path in ("/app.js", "/sky.js", "/shaders/common.glsl"):
        _assert_refused(server, path, {"Sec-Fetch-Site": site, "Sec-Fetch-Mode": "no-cors",
                                       "Sec-Fetch-Dest": "script"})
    _assert_refused(server, "/", {"Sec-Fetch-Site": site, "Sec-Fetch-Mode": "navigate",
                                  "Sec-Fetch-Dest": "iframe"})
    st, h, _ = _request(server, "/", {"Sec-Fetch-Site": site, "Sec-Fetch-Mode": "navigate",
                                      "Sec-Fetch-Dest": "document"})
    assert st == 200 and h["Cross-Origin-Opener-Policy"] == "same-origin"


def test_token_required(server):
    from skydome.viewer.server import make_server

    other = make_server("127.0.0.1", 0)      # another server start: another token
    try:
        assert other.token != server.token and len(server.token) >= 32
        for path in API_PATHS:
            for headers in ({}, {"X-Skydome-Token": ""}, {"X-Skydome-Token": "x" * 43},
                            {"X-Skydome-Token": other.token},
                            {"X-Skydome-Token": server.token[:-1]},
                            {"X-Skydome-Token": server.token + "A"},
                            {"X-Skydome-Token": server.token.upper()}):
                assert "X-Skydome-Token" in _assert_refused(server, path, headers)
    finally:
        other.server_close()
    c = http.client.HTTPConnection("127.0.0.1", _port(server), timeout=10)
    c.putrequest("GET", "/api/models", skip_accept_encoding=True)
    c.putheader("X-Skydome-Token", server.token)
    c.putheader("X-Skydome-Token", server.token)
    c.endheaders()
    assert c.getresponse().status == 403
    c.close()
    assert _token(server) == server.token
    st, _, _ = _request(server, "/api/models", {"X-Skydome-Token": server.token})
    assert st == 200


def test_page_token_changes_with_each_start():
    from skydome.viewer.server import make_server

    tokens = set()
    for _ in range(3):
        srv = make_server("127.0.0.1", 0)
        tokens.add(srv.token)
        srv.server_close()
    assert len(tokens) == 3


@pytest.mark.parametrize("query,message", [
    ("model=precomputed&observer_altitude_m=nan", "observer_altitude_m = nan is not a finite"),
    ("model=precomputed&observer_altitude_m=inf", "observer_altitude_m = inf is not a finite"),
    ("model=precomputed&observer_altitude_m=-1", "observer_altitude_m = -1"),
    ("model=precomputed&observer_altitude_m=1e9", "observer_altitude_m = 1e+09"),
    ("model=precomputed&turbidity=nan", "turbidity = nan is not a finite number"),
    ("model=precomputed&turbidity=3.3&sun_elevation=nan", "sun_elevation"),
    ("model=precomputed&turbidity=3.3&sun_azimuth=inf", "sun_azimuth"),
    ("model=precomputed&turbidity=3.3&lat=48&lon=16", "time missing"),
    ("model=hillaire2020&observer_altitude_m=nan", "observer_altitude_m = nan"),
    ("model=hillaire2020&turbidity=-3", "turbidity = -3"),
    ("model=dobashi2002&n_planes=500", "n_planes = 500 is out of range [1, 128]"),
    ("model=dobashi2002&turbidity=nan", "turbidity = nan"),
])
def test_bad_parameters_refused_before_any_bake(server, query, message):
    """Every value is checked before a table is built: 400 at once, no bake started, no
    table set added, nothing in the cache folder (the earlier server answered
    observer_altitude_m=nan with 400 after a 2.2 s bake and a 43 MB cache entry)."""
    t0 = time.monotonic()
    err = _assert_refused(server, "/api/scene?" + query, {"X-Skydome-Token": server.token},
                          status=400)
    assert message in err, err
    assert time.monotonic() - t0 < 10.0


# -- the bake queue ----------------------------------------------------------------------------
def _open(srv, path, token=True):
    """A connected socket that has sent one complete request and reads nothing yet."""
    s = socket.create_connection(("127.0.0.1", _port(srv)), timeout=20)
    hdr = f"X-Skydome-Token: {srv.token}\r\n" if token else ""
    s.sendall(f"GET {path} HTTP/1.1\r\nHost: 127.0.0.1:{_port(srv)}\r\n{hdr}\r\n".encode())
    return s


def _read_all(s) -> bytes:
    out = b""
    while True:
        chunk = s.recv(65536)
        if not chunk:
            return out
        out += chunk


def _wait(cond, timeout_s=15.0):
    t0 = time.monotonic()
    while not cond():
        assert time.monotonic() - t0 < timeout_s, "condition not reached"
        time.sleep(0.02)


def _reset(s):
    """Close with a TCP reset (as a browser tab that is killed)."""
    s.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, struct.pack("ii", 1, 0))
    s.close()


def test_bake_queue_bounded_and_gone_clients_not_baked(server):
    """While a bake runs (the test holds the server's bake slot, as a running bake
    does), at most BAKE_QUEUE requests wait; the rest get 503 with Retry-After at once.
    Waiting requests whose clients hang up are dropped: nothing is baked for them."""
    q = server.bake_queue
    n_wait = q.max_waiting
    before = (q.started, q.cancelled, _viewer_tables())
    with q.hold():
        waiting = [_open(server, f"/api/scene?model=hillaire2020&turbidity={3 + 0.1 * i}")
                   for i in range(n_wait)]
        _wait(lambda: q.waiting == n_wait)
        t0 = time.monotonic()
        for i in range(5):
            st, h, body = _request(server, f"/api/scene?model=precomputed&turbidity={4 + 0.1 * i}",
                                   {"X-Skydome-Token": server.token})
            assert st == 503 and int(h["Retry-After"]) > 0, (st, body)
        assert time.monotonic() - t0 < 5.0
        # requests of the analytic models never wait for a bake
        st, _, _ = _request(server, "/api/scene?model=preetham1999&sun_elevation=20",
                            {"X-Skydome-Token": server.token})
        assert st == 200
        for i, s in enumerate(waiting):
            s.close() if i % 2 else _reset(s)
        _wait(lambda: q.waiting == 0)
    assert q.started == before[0] + 1                 # the test's own hold, no bake
    assert q.cancelled == before[1] + n_wait
    assert _viewer_tables() == before[2]


# -- many connections --------------------------------------------------------------------------
def test_burst_of_concurrent_requests_all_answered(server):
    """50 concurrent requests (static files and light API answers, as a page's start and
    more): every one answered 200, within a bounded time, no worker thread per request."""
    paths = ["/", "/app.js", "/sky.js", "/style.css", "/shaders/common.glsl", "/api/models",
             "/api/scene?model=preetham1999&sun_elevation=30",
             "/api/scene?model=oneil2005&sun_elevation=10"]
    results: list = []
    threads_before = threading.active_count()
    peak = [0]

    def one(i):
        path = paths[i % len(paths)]
        hdr = {"X-Skydome-Token": server.token} if path.startswith("/api/") else {}
        results.append(_request(server, path, hdr, timeout=60)[0])
        peak[0] = max(peak[0], threading.active_count())

    ts = [threading.Thread(target=one, args=(i,)) for i in range(50)]
    t0 = time.monotonic()
    for t in ts:
        t.start()
    for t in ts:
        t.join(90)
    assert results.count(200) == 50, results
    assert time.monotonic() - t0 < 60
    # the 50 client threads of this test, and no server thread beyond the fixed pool
    assert peak[0] <= threads_before + 50


def test_burst_of_bakes_bounded(server):
    """50 concurrent bake requests while a bake runs: BAKE_QUEUE wait, the others are
    503 at once; nothing baked (the clients of the waiting ones hang up)."""
    q = server.bake_queue
    before = (q.started, _viewer_tables())
    refused = q.refused
    statuses: list = []
    with q.hold():
        socks = [_open(server, f"/api/scene?model=precomputed&turbidity={6 + 0.01 * i}")
                 for i in range(50)]
        _wait(lambda: q.refused == refused + 50 - q.max_waiting and q.waiting == q.max_waiting)
        for s in socks:
            s.settimeout(0.3)
            try:
                data = s.recv(65536)
            except TimeoutError:
                data = b""
            statuses.append(data.split(b" ", 2)[1] if data.startswith(b"HTTP/") else b"wait")
            s.close()
        _wait(lambda: q.waiting == 0)
    assert statuses.count(b"503") == 50 - q.max_waiting, statuses
    assert statuses.count(b"wait") == q.max_waiting
    assert (q.started, _viewer_tables()) == (before[0] + 1, before[1])


def test_idle_and_half_open_connections_closed(server):
    """50 connections that send nothing, 10 that stop inside the request head, and 5
    that send a byte a second (slow-loris): all closed by the server (idle after
    IDLE_TIMEOUT_S, the others at REQUEST_TIMEOUT_S), while a normal request is
    answered at once; no thread per connection."""
    threads_before = threading.active_count()
    port = _port(server)
    idle = [socket.create_connection(("127.0.0.1", port), timeout=30) for _ in range(50)]
    partial = []
    for _ in range(10):
        s = socket.create_connection(("127.0.0.1", port), timeout=30)
        s.sendall(f"GET /api/models HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\n".encode())
        partial.append(s)
    slow = [socket.create_connection(("127.0.0.1", port), timeout=30) for _ in range(5)]
    t0 = time.monotonic()
    st, _, _ = _request(server, "/app.js", timeout=5)
    assert st == 200 and time.monotonic() - t0 < 3.0
    assert threading.active_count() <= threads_before + 1
    closed_at: dict = {}
    head = f"GET /api/models HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\nX-Pad: ".encode() + b"a" * 40
    sent = 0
    while len(closed_at) < 65 and time.monotonic() - t0 < 30:
        if sent < len(head):
            for s in slow:
                if s not in closed_at:
                    try:
                        s.send(head[sent:sent + 1])
                    except OSError:
                        closed_at[s] = time.monotonic() - t0
            sent += 1
        for s in idle + partial + slow:
            if s in closed_at:
                continue
            s.settimeout(0.0)
            try:
                if s.recv(4096) == b"":
                    closed_at[s] = time.monotonic() - t0
            except BlockingIOError:
                pass
            except OSError:
                closed_at[s] = time.monotonic() - t0
        time.sleep(1.0)
    for s in idle + partial + slow:
        s.close()
    assert len(closed_at) == 65, f"{65 - len(closed_at)} connections still open after 30 s"
    t_idle = max(closed_at[s] for s in idle)
    t_rest = max(closed_at[s] for s in partial + slow)
    assert server.IDLE_TIMEOUT_S - 1 <= t_idle <= server.IDLE_TIMEOUT_S + 3, t_idle
    assert t_rest <= server.IDLE_TIMEOUT_S + server.REQUEST_TIMEOUT_S + 3, t_rest


# -- a client that hangs up --------------------------------------------------------------------
def _start_view(*args):
    env = dict(os.environ, PYTHONPATH=str(ROOT / "src"))
    p = subprocess.Popen([sys.executable, "-m", "skydome.cli", "view", "--port", "0",
                          "--no-browser", *args], stdout=subprocess.PIPE,
                         stderr=subprocess.PIPE, text=True, env=env)
    url = p.stdout.readline().strip()
    assert url.startswith("http://127.0.0.1:"), (url, p.stderr.read() if p.poll() else "")
    return p, int(url.rstrip("/").rsplit(":", 1)[1])


def _drop_clients(port, n=50):
    """n clients that hang up: half reset the connection right after a request for the
    largest static file, half in the middle of the request head."""
    for i in range(n):
        s = socket.create_connection(("127.0.0.1", port), timeout=10)
        if i % 2:
            s.sendall(f"GET /sky.js HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\n\r\n".encode())
        else:
            s.sendall(b"GET /sky.js HTTP/1.1\r\nHo")
        _reset(s)


@pytest.mark.parametrize("verbose", [False, True], ids=["quiet", "verbose"])
def test_dropped_clients_no_traceback(verbose):
    """50 clients that hang up (the earlier server printed 6 907 lines of tracebacks for
    300): nothing on stderr, or with --verbose one line each at most, never a traceback."""
    p, port = _start_view(*(["--verbose"] if verbose else []))
    try:
        _drop_clients(port)
        st = http.client.HTTPConnection("127.0.0.1", port, timeout=10)
        st.request("GET", "/")
        assert st.getresponse().status == 200
        st.close()
        time.sleep(0.5)
        p.send_signal(signal.SIGINT)
        assert p.wait(timeout=15) == 0
        err = p.stderr.read()
    finally:
        if p.poll() is None:
            p.kill()
            p.wait()
    assert "Traceback" not in err
    lines = err.splitlines()
    if not verbose:
        assert lines == [], lines[:5]
    else:
        # one line per dropped client at most, else the access log's one line per request
        drops = [ln for ln in lines if ln.startswith("skydome view: client")]
        assert 1 <= len(drops) <= 50
        assert all(ln.startswith("127.0.0.1 - - [") for ln in lines if ln not in drops), lines
        assert len(lines) <= 2 * 50 + 1


# -- a legitimate bake writes nothing to the table cache ----------------------------------------
def test_legit_bake_stays_in_memory_and_unsent_when_client_gone(server, cache_dir):
    """The page's own precomputed request bakes (in memory, at the viewer's sizes) and
    writes nothing to the table cache folder; a client that hangs up during the bake
    gets nothing sent, and the next request for the same tables is answered from memory
    without a new bake."""
    q = server.bake_queue
    started, unsent = q.started, server.counts["unsent"]
    s = _open(server, "/api/scene?model=precomputed&turbidity=2.7&sun_elevation=20")
    _wait(lambda: q.started == started + 1, 30)
    s.close()
    t0 = time.monotonic()
    _wait(lambda: server.counts["unsent"] == unsent + 1, 600)
    t_bake = time.monotonic() - t0
    tables = _viewer_tables()
    st, _, body = _request(server, "/api/scene?model=precomputed&turbidity=2.7&sun_elevation=35",
                           {"X-Skydome-Token": server.token}, timeout=600)
    assert st == 200 and json.loads(body)["model"] == "precomputed"
    assert q.started == started + 2 and _viewer_tables() == tables
    assert list(cache_dir.rglob("*")) == []
    print(f"viewer precomputed bake: {t_bake:.1f} s after the client left")


# -- the attacks from a real browser -------------------------------------------------------------
_ATTACK_PAGE = """<!doctype html><html><head><title>attack</title></head><body>
<img src="{v}/api/scene?model=precomputed&turbidity=3.3">
<iframe src="{v}/api/scene?model=precomputed&turbidity=3.4"></iframe>
<script>
const v = "{v}";
window.done = 0;
const tick = () => {{ window.done += 1; }};
fetch(v + "/api/scene?model=precomputed&turbidity=3.5", {{ mode: "no-cors" }}).then(tick, tick);
fetch(v + "/api/scene?model=precomputed&turbidity=3.6",
      {{ headers: {{ "X-Skydome-Token": "guess" }} }}).then(tick, tick);
fetch(v + "/").then((r) => r.text()).then((t) => {{ window.read = t; tick(); }}, tick);
</script></body></html>"""


@pytest.fixture(scope="module")
def attacker_site(server):
    """A page on another origin that fires the API at the viewer (served on 127.0.0.1 at
    another port; the browser reaches it as http://evil.test:PORT/ by a resolver rule)."""
    from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer

    body = _ATTACK_PAGE.format(v=f"http://127.0.0.1:{_port(server)}").encode()

    class Attacker(BaseHTTPRequestHandler):
        def do_GET(self):  # noqa: N802
            self.send_response(200)
            self.send_header("Content-Type", "text/html")
            self.send_header("Content-Length", str(len(body)))
            self.end_headers()
            self.wfile.write(body)

        def log_message(self, *a):
            pass

    srv = ThreadingHTTPServer(("127.0.0.1", 0), Attacker)
    t = threading.Thread(target=srv.serve_forever, daemon=True)
    t.start()
    yield srv.server_address[1]
    srv.shutdown()
    srv.server_close()


@pytest.fixture(scope="module")
def browser():
    from _viewer import CHROMIUM, CHROMIUM_ARGS, have_browser

    if not have_browser():
        pytest.skip("headless Chromium or Playwright missing (scripts/_setup test installs them)")
    from playwright.sync_api import sync_playwright

    with sync_playwright() as p:
        b = p.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS + [
            "--host-resolver-rules=MAP evil.test 127.0.0.1"])
        yield b
        b.close()


@pytest.mark.parametrize("site", ["evil.test", "127.0.0.1"], ids=["cross-site", "same-site"])
def test_browser_page_elsewhere_cannot_drive_the_api(server, attacker_site, browser, site):
    """A real page on another origin (another site, or another port of 127.0.0.1) fires
    an <img>, an <iframe>, a no-cors fetch, a fetch with a guessed token and a read of
    the viewer's page: no bake starts, the refused requests reach the server and are
    refused, and the page cannot read the viewer's page (nor its token)."""
    q = server.bake_queue
    before = (q.started, _viewer_tables(), server.counts["refused"])
    page = browser.new_page()
    try:
        page.goto(f"http://{site}:{attacker_site}/")
        _wait(lambda: page.evaluate("() => window.done") >= 3, 30)
        _wait(lambda: server.counts["refused"] >= before[2] + 3, 10)
        assert page.evaluate("() => window.read === undefined")
        html = page.content()
    finally:
        page.close()
    assert server.token not in html
    assert (q.started, _viewer_tables()) == before[:2]


def test_browser_dns_rebinding_refused(server, browser):
    """The viewer reached under another name (a DNS-rebinding page, here by a resolver
    rule): the page and the API are 403, no token is served."""
    page = browser.new_page()
    try:
        r = page.goto(f"http://evil.test:{_port(server)}/")
        assert r.status == 403
        assert server.token not in page.content()
        r = page.goto(f"http://evil.test:{_port(server)}/api/models")
        assert r.status == 403
    finally:
        page.close()


def test_browser_own_page_sends_token(server, browser):
    """The viewer's own page in the same browser: its API requests carry the token and
    are answered (the model list fills the model menu)."""
    page = browser.new_page()
    try:
        page.goto(server.url)
        _wait(lambda: page.evaluate(
            "() => document.getElementById('model').options.length") >= 6, 60)
        assert page.evaluate("() => document.getElementById('error').textContent") == ""
    finally:
        page.close()
