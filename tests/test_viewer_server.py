"""Security and behaviour of the viewer's local server (no browser needed).

Raw HTTP requests (http.client sends the path as given, nothing normalised) try path
traversal in its usual disguises; the server must answer 400/404 without the target's
bytes. Bad API parameters give 400 with the CLI's own message; non-local binds are
refused; ``skydome view`` stops cleanly on SIGINT and SIGTERM.
"""

from __future__ import annotations

import http.client
import json
import os
import re
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest

from _viewer import viewer_url  # noqa: F401 - fixture

ROOT = Path(__file__).resolve().parents[1]


_TOKENS: dict[str, str] = {}


def _token(url: str) -> str:
    """The API token the server wrote into its page, read as the page's own script does."""
    if url not in _TOKENS:
        status, _, body = _get(url, "/")
        m = re.search(rb'<meta name="skydome-token" content="([A-Za-z0-9_-]+)">', body)
        assert status == 200 and m, body[:200]
        _TOKENS[url] = m.group(1).decode()
    return _TOKENS[url]


def _get(url: str, path: str, method: str = "GET"):
    host, port = url.split("//")[1].rstrip("/").rsplit(":", 1)
    token = _token(url) if path.startswith("/api/") else None
    c = http.client.HTTPConnection(host, int(port), timeout=10)
    c.putrequest(method, path, skip_host=False, skip_accept_encoding=True)
    if token is not None:
        c.putheader("X-Skydome-Token", token)
    c.endheaders()
    r = c.getresponse()
    body = r.read()
    c.close()
    return r.status, dict(r.getheaders()), body


SECRET = (ROOT / "pyproject.toml").read_bytes()[:60]
PASSWD = b"root:"

TRAVERSALS = [
    "/../pyproject.toml", "/../../pyproject.toml", "/..%2fpyproject.toml",
    "/%2e%2e/%2e%2e/%2e%2e/pyproject.toml", "/%2E%2E/%2E%2E/etc/passwd",
    "/%252e%252e/%252e%252e/etc/passwd", "/..%252f..%252fetc/passwd",
    "/....//....//etc/passwd", "/shaders/../../server.py", "/shaders/..%5c..%5cserver.py",
    "/..\\..\\server.py", "//etc/passwd", "/etc/passwd", "/%2fetc%2fpasswd",
    "/server.py", "/__init__.py", "/static/index.html/../../server.py",
    "/index.html%00.py", "http://example.com/etc/passwd", "/./././../cli.py",
]


@pytest.mark.parametrize("path", TRAVERSALS)
def test_traversal_refused(viewer_url, path):  # noqa: F811
    status, headers, body = _get(viewer_url, path)
    assert status in (400, 404), (path, status)
    assert SECRET not in body and PASSWD not in body and b"import" not in body
    assert headers["Content-Security-Policy"].startswith("default-src 'none'")


def test_static_files_served_with_headers(viewer_url):  # noqa: F811
    for path, ctype in (("/", "text/html"), ("/index.html", "text/html"),
                        ("/app.js", "text/javascript"), ("/shaders/common.glsl", "text/plain")):
        status, headers, body = _get(viewer_url, path)
        assert status == 200 and headers["Content-Type"].startswith(ctype), path
        csp = headers["Content-Security-Policy"]
        assert "default-src 'none'" in csp and "script-src 'self'" in csp
        assert "unsafe" not in csp and "http" not in csp
        assert headers["X-Content-Type-Options"] == "nosniff"


def test_no_external_resources_in_static_files():
    from skydome.viewer.server import static_files

    files = static_files()
    assert {"/index.html", "/app.js", "/sky.js", "/shaders/preetham1999.glsl"} <= set(files)
    for path, f in files.items():
        text = f.read_text()
        assert "http://" not in text and "https://" not in text and "//cdn" not in text, path


def test_symlinks_out_of_static_are_not_served(tmp_path, monkeypatch):
    from skydome.viewer import server

    static = tmp_path / "static"
    static.mkdir()
    (static / "index.html").write_text("<p>ok</p>")
    outside = tmp_path / "secret.js"
    outside.write_text("secret")
    (static / "link.js").symlink_to(outside)
    (static / "dirlink").symlink_to(tmp_path, target_is_directory=True)
    monkeypatch.setattr(server, "static_dir", lambda: static)
    files = server.static_files()
    assert "/index.html" in files
    assert not any("link" in p or "secret" in p for p in files)


def test_methods_other_than_get_refused(viewer_url):  # noqa: F811
    for method in ("POST", "PUT", "DELETE"):
        status, headers, _ = _get(viewer_url, "/api/scene?model=preetham1999", method)
        assert status == 405 and headers["Allow"] == "GET, HEAD"


@pytest.mark.parametrize("query,message", [
    # the messages of the model constructors, which the CLI prints as "error: <message>"
    ("model=preetham1999&turbidity=20", "turbidity = 20 is out of range [2, 10]"),
    ("model=preetham1999&sun_elevation=95", "sun_elevation = 95 deg is out of range [-90, 90] deg"),
    ("model=preetham1999&sun_elevation=-4", "out of range [0, 90] deg for model 'preetham1999'"),
    ("model=oneil2005&kr=abc", "kr = 'abc' is not a valid float"),
    ("model=oneil2005&samples=2.5", "samples = '2.5' is not a valid int"),
    ("model=hoffman_preetham2002&g=1.5", "g = 1.5 is out of range [0, 0.99]"),
    ("model=hoffman_preetham2002&phase=bogus", "phase"),
    ("model=nosuch", "model = 'nosuch' is not one of preetham1999"),
    ("", "model is missing"),
    ("model=preetham1999&foo=1", "unknown parameter 'foo'"),
    ("model=preetham1999&turbidity=3&turbidity=4", "given twice: turbidity"),
    ("model=preetham1999&turbidity=nan", "turbidity = nan is not a finite number"),
    ("model=preetham1999&sun_elevation=10&lat=48", "not both"),
    ("model=preetham1999&lat=48&lon=16", "time missing"),
    ("model=dobashi2002&shafts=maybe", "shafts = 'maybe' is not a boolean"),
    ("model=dobashi2002&n_planes=500", "n_planes = 500 is out of range [1, 128]"),
    ("model=dobashi2002&turbidity=0.5", "turbidity = 0.5 is out of range [1, 32]"),
])
def test_bad_parameters_400(viewer_url, query, message):  # noqa: F811
    status, headers, body = _get(viewer_url, "/api/scene?" + query)
    assert status == 400
    assert headers["Content-Type"] == "application/json"
    err = json.loads(body)["error"]
    assert message in err, err


def test_api_message_is_the_cli_message(viewer_url):  # noqa: F811
    """The same bad value through `skydome render` and through the API: the same message,
    naming the API's parameter there and the command-line option (``--turbidity``) here."""
    status, _, body = _get(viewer_url, "/api/scene?model=preetham1999&turbidity=20&sun_elevation=20")
    assert status == 400
    env = dict(os.environ, PYTHONPATH=str(ROOT / "src"))
    r = subprocess.run([sys.executable, "-m", "skydome.cli", "render", "--model", "preetham1999",
                        "--turbidity", "20", "--sun-elevation", "20", "--out", "never.exr"],
                       capture_output=True, text=True, env=env, cwd=ROOT / "tests", timeout=120)
    assert r.returncode == 2
    assert r.stderr.strip() == "error: --" + json.loads(body)["error"]
    assert not (ROOT / "tests" / "never.exr").exists()


def test_scene_by_place_and_time(viewer_url):  # noqa: F811
    status, _, body = _get(viewer_url, "/api/scene?model=preetham1999&lat=48.21&lon=16.37"
                                       "&time=2026-06-21T12:00%2B02:00")
    assert status == 200
    sun = json.loads(body)["sun"]
    # Vienna at local noon near the June solstice: elevation 90 - 48.21 + 23.44 = 65.2 deg
    # (solar noon is at about 12:58 CEST, so an hour before: a little lower, east of south)
    assert 58.0 < sun["elevation_deg"] < 65.3 and 120.0 < sun["azimuth_deg"] < 180.0


def test_models_route(viewer_url):  # noqa: F811
    status, _, body = _get(viewer_url, "/api/models")
    assert status == 200
    models = json.loads(body)
    assert set(models) == {"preetham1999", "hoffman_preetham2002", "oneil2005", "hillaire2020",
                           "precomputed", "fitted", "dobashi2002"}
    assert [p["name"] for p in models["preetham1999"]["parameters"]] == ["turbidity"]
    assert [p["name"] for p in models["dobashi2002"]["parameters"]] == ["turbidity", "shafts", "n_planes"]
    assert [p["name"] for p in models["fitted"]["parameters"]] == [
        "aerosol_optical_depth", "ground_albedo", "observer_altitude_m"]


@pytest.mark.parametrize("host", ["0.0.0.0", "::", "192.168.1.10", "example.com", ""])
def test_non_local_bind_refused(host):
    from skydome.viewer.server import make_server

    with pytest.raises(ValueError, match="binds only to"):
        make_server(host, 0)


def test_cli_refuses_non_local_host():
    env = dict(os.environ, PYTHONPATH=str(ROOT / "src"))
    r = subprocess.run([sys.executable, "-m", "skydome.cli", "view", "--host", "0.0.0.0",
                        "--no-browser"], capture_output=True, text=True, env=env, timeout=60)
    assert r.returncode == 2
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: host = '0.0.0.0' is not allowed")


def _start_view():
    env = dict(os.environ, PYTHONPATH=str(ROOT / "src"))
    p = subprocess.Popen([sys.executable, "-m", "skydome.cli", "view", "--port", "0",
                          "--no-browser"], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                         text=True, env=env)
    url = p.stdout.readline().strip()
    assert url.startswith("http://127.0.0.1:"), (url, p.stderr.read() if p.poll() else "")
    return p, url


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM], ids=["SIGINT", "SIGTERM"])
def test_view_stops_cleanly_on_signal(sig):
    p, url = _start_view()
    try:
        status, _, body = _get(url, "/")
        assert status == 200 and b"skydome viewer" in body
        p.send_signal(sig)
        rc = p.wait(timeout=10)
        assert rc == 0, p.stderr.read()
        assert "Traceback" not in p.stderr.read()
        port = int(url.rstrip("/").rsplit(":", 1)[1])
        with pytest.raises(OSError):
            socket.create_connection(("127.0.0.1", port), timeout=2).close()
    finally:
        if p.poll() is None:
            p.kill()
            p.wait()


def test_lut_route_validates(viewer_url):  # noqa: F811
    for query, message in (("", "takes key and name"), ("key=x", "takes key and name"),
                           ("key=x&name=y&z=1", "takes key and name"),
                           ("key=nosuch&name=multiple_scattering", "not a baked table set")):
        status, _, body = _get(viewer_url, "/api/lut?" + query)
        assert status == 400 and message in json.loads(body)["error"], query
