"""The viewer's local HTTP server (standard library only).

Why ``http.server``: the viewer serves a handful of static files and one small JSON API to
one local browser. :class:`http.server.HTTPServer` does that without a new dependency, and
every rule below is a few explicit lines that the tests exercise (tests/test_viewer_server.py,
tests/test_viewer_security.py):

* binds 127.0.0.1 (or ::1 / localhost) only; any other host is refused before a socket
  is opened;
* answers only requests whose ``Host`` is a loopback name with the server's port
  (``127.0.0.1:PORT``, ``localhost:PORT``, ``[::1]:PORT``): a page that rebinds its own
  DNS name to 127.0.0.1 gets 403 for everything, the page included;
* refuses cross-site requests before any work: an ``Origin`` other than the server's own,
  or ``Sec-Fetch-Site`` ``cross-site`` or ``same-site`` (another port of localhost is the
  same site), is 403; the one exception is a top-level navigation to the page itself
  (a link to the viewer), which does no work and cannot read the answer;
* every ``/api/`` request must carry the page's token (``X-Skydome-Token``): random, made
  when the server starts, written into the served page, so that only the page (or a
  client that read the page) can make the server work; a missing or wrong token is 403
  before anything is parsed. A custom header also makes any cross-origin ``fetch`` a
  preflighted one, which the server does not grant (OPTIONS is 405);
* serves only the files listed in its own ``static/`` folder, by exact name: no path is
  ever joined from the request, so ``..``, encoded (``%2e%2e``, ``%2f``), doubled
  (``%252e``), backslash and absolute paths, and symlinks out of the folder cannot reach
  anything else (they are 404);
* ``GET /api/models`` lists the models and their parameters; ``GET /api/scene?model=...``
  returns the shader's numbers (:func:`skydome.viewer.scene.shader_scene`) after every
  parameter is validated (:func:`check_scene_request`: 400 with ``{"error": message}``,
  the CLI's message, before anything is built); ``GET /api/lut?key=...&name=...`` one
  baked table as raw float32;
* models that bake tables (all but the analytic preetham1999, hoffman_preetham2002 and
  oneil2005) run one at a time (:class:`BakeQueue`): at most ``BAKE_QUEUE`` requests wait,
  more get 503 with ``Retry-After``; a waiting request whose client has gone is dropped
  without baking, and a finished bake whose client has gone is not sent. A bake that has
  started runs to its end (the precomputation cannot be interrupted); its tables stay in
  memory only: the viewer's precomputed model does not read or write the on-disk table
  cache (``cache=False``), so no request can evict the user's own entries there;
* connections: a listen backlog of ``LISTEN_BACKLOG``, a fixed pool of ``WORKERS`` threads;
  a connection reaches a worker only once its first bytes have arrived (idle or half-open
  connections wait in one selector thread and are closed after ``IDLE_TIMEOUT_S``), the
  request head must be complete within ``REQUEST_TIMEOUT_S``, every answer closes its
  connection (no keep-alive to pin a worker), and a client that hangs up costs no
  traceback (one line on stderr with ``verbose``);
* every response carries a strict Content-Security-Policy (same origin only, no inline
  script, no external resources), ``X-Content-Type-Options: nosniff``,
  ``Cross-Origin-Resource-Policy: same-origin``, no caching of the API or the page, and
  ``Referrer-Policy: no-referrer``; only GET and HEAD are allowed.
"""

from __future__ import annotations

import contextlib
import hmac
import io
import json
import queue
import secrets
import selectors
import signal
import socket
import sys
import threading
import time
from http import HTTPStatus
from http.server import BaseHTTPRequestHandler, HTTPServer
from importlib import resources
from pathlib import Path
from typing import Any, Callable
from urllib.parse import parse_qsl, urlsplit

__all__ = ["LOCAL_HOSTS", "CSP", "TOKEN_HEADER", "BakeQueue", "ViewerServer", "make_server",
           "serve", "static_files", "check_scene_request"]

#: Host names the server may bind to.
LOCAL_HOSTS = ("127.0.0.1", "::1", "localhost")

#: Content-Security-Policy of every response.
CSP = ("default-src 'none'; script-src 'self'; style-src 'self'; img-src 'self' data: blob:; "
       "connect-src 'self'; base-uri 'none'; form-action 'none'; frame-ancestors 'none'")

#: The request header that carries the page's token on every /api/ request.
TOKEN_HEADER = "X-Skydome-Token"

#: The page's placeholder for the token (index.html); the server fills it in.
_TOKEN_META = b'<meta name="skydome-token" content="">'

#: Models whose /api/scene answer is a few coefficients (milliseconds, no tables): they do
#: not wait in the bake queue. Every other model does (a table build or bake).
QUEUE_FREE_MODELS = frozenset({"preetham1999", "hoffman_preetham2002", "oneil2005"})

_TYPES = {".html": "text/html; charset=utf-8", ".js": "text/javascript; charset=utf-8",
          ".css": "text/css; charset=utf-8", ".glsl": "text/plain; charset=utf-8",
          ".json": "application/json", ".png": "image/png", ".svg": "image/svg+xml"}

_MAX_QUERY = 4096


def static_dir() -> Path:
    """The package's static folder."""
    return Path(str(resources.files("skydome.viewer") / "static"))


def static_files() -> dict[str, Path]:
    """URL path -> file for every regular file in the static folder (no symlinks, nothing
    whose real path leaves the folder)."""
    root = static_dir().resolve()
    out: dict[str, Path] = {}
    for p in sorted(root.rglob("*")):
        if p.is_symlink() or not p.is_file() or p.suffix not in _TYPES:
            continue
        real = p.resolve()
        if root not in real.parents:
            continue
        out["/" + real.relative_to(root).as_posix()] = real
    out["/"] = out.get("/index.html", root / "index.html")
    return out


# -- validation before work ---------------------------------------------------------------
def check_scene_request(query: dict[str, str]) -> tuple[str, dict, dict]:
    """Validate an /api/scene query completely, building nothing: the model name, every
    parameter against its declared type and range, the sun (angles, or place and time)
    and the model's sun elevation range. Returns (model, sun keywords, model keywords);
    raises ValueError or TypeError with the message the CLI prints for the same value.

    :func:`skydome.viewer.scene.shader_scene` checks the same again as it builds; this
    runs first so that a request with a bad value (``observer_altitude_m=nan``) never
    starts a table build."""
    from skydome.sun import sun_from_options
    from skydome.viewer import scene

    model, sun_kw, params = scene.parse_request(query)
    sun = sun_from_options(**sun_kw)
    cls = scene.viewer_class(model)
    if cls is scene.Dobashi2002View:
        cls(sun, **params)                       # validation only: no table in __init__
        return model, sun_kw, params
    declared = {p.name: p for p in cls.parameters}
    for name, value in params.items():
        declared[name].validate(value)
    if not cls.sun_in_range(sun.elevation_deg) and cls.sun_outside_range == "raise":
        raise ValueError(cls._sun_range_message(sun.elevation_deg))
    if model == "oneil2005" and params.get("samples", 2) > scene.ONEIL_MAX_SAMPLES:
        raise ValueError(f"samples = {params['samples']} is out of range [1, "
                         f"{scene.ONEIL_MAX_SAMPLES}] in the viewer")
    return model, sun_kw, params


# -- one bake at a time -------------------------------------------------------------------
class QueueFull(Exception):
    """The bake queue holds its maximum of waiting requests."""


class BakeQueue:
    """One bake at a time, at most ``max_waiting`` requests waiting for it.

    :meth:`enter` returns True once the caller holds the bake slot (call :meth:`leave`
    after the bake), False where ``alive()`` turned false while it waited or just before
    it would start (its client hung up: nothing is baked), and raises :class:`QueueFull`
    where ``max_waiting`` requests already wait. Counters: ``started`` (bakes begun),
    ``cancelled`` (requests dropped because their client had gone), ``refused`` (queue
    full)."""

    POLL_S = 0.2

    def __init__(self, max_waiting: int):
        self.max_waiting = int(max_waiting)
        self._cond = threading.Condition()
        self._busy = False
        self._waiting = 0
        self.started = 0
        self.cancelled = 0
        self.refused = 0

    @property
    def waiting(self) -> int:
        return self._waiting

    def enter(self, alive: Callable[[], bool] = lambda: True) -> bool:
        with self._cond:
            if self._busy and self._waiting >= self.max_waiting:
                self.refused += 1
                raise QueueFull
            self._waiting += 1
            try:
                while self._busy:
                    self._cond.wait(self.POLL_S)
                    if self._busy and not alive():
                        self.cancelled += 1
                        return False
                if not alive():
                    self.cancelled += 1
                    return False
                self._busy = True
                self.started += 1
                return True
            finally:
                self._waiting -= 1

    def leave(self) -> None:
        with self._cond:
            self._busy = False
            self._cond.notify_all()

    @contextlib.contextmanager
    def hold(self):
        """Hold the bake slot (as a running bake does) for the ``with`` block."""
        if not self.enter():
            raise RuntimeError("bake slot not taken")
        try:
            yield self
        finally:
            self.leave()


def client_alive(sock: socket.socket) -> bool:
    """Whether the client of ``sock`` is still there: False once it has closed its side
    (a zero-byte peek) or reset the connection; True while nothing or more data waits."""
    old = sock.gettimeout()
    try:
        sock.settimeout(0.0)
        return sock.recv(1, socket.MSG_PEEK) != b""
    except BlockingIOError:
        return True
    except OSError:
        return False
    finally:
        with contextlib.suppress(OSError):
            sock.settimeout(old)


# -- the request handler ------------------------------------------------------------------
class _DeadlineReader(io.RawIOBase):
    """A socket's input with one deadline for everything read through it (the request
    head): a client that sends a byte every few seconds cannot hold a worker longer."""

    def __init__(self, sock: socket.socket, deadline: float):
        self._sock, self._deadline = sock, deadline

    def readable(self) -> bool:
        return True

    def readinto(self, b) -> int:
        left = self._deadline - time.monotonic()
        if left <= 0:
            raise TimeoutError("request not complete in time")
        self._sock.settimeout(left)
        return self._sock.recv_into(b)


class _Writer(io.BufferedIOBase):
    """Unbuffered socket output (``sendall``: no partial writes)."""

    def __init__(self, sock: socket.socket):
        self._sock = sock

    def writable(self) -> bool:
        return True

    def write(self, b) -> int:
        self._sock.sendall(b)
        with memoryview(b) as view:
            return view.nbytes


class _Handler(BaseHTTPRequestHandler):
    server_version = "skydome-viewer"
    sys_version = ""
    protocol_version = "HTTP/1.1"

    def setup(self):
        self.connection = self.request
        deadline = time.monotonic() + self.server.request_timeout_s
        self.rfile = io.BufferedReader(_DeadlineReader(self.connection, deadline))
        self.wfile = _Writer(self.connection)

    def finish(self):
        # the socket itself is closed by the server (shutdown_request)
        with contextlib.suppress(OSError, ValueError):
            self.rfile.close()

    def handle(self):
        # one request per connection: the answer says "Connection: close"
        self.close_connection = True
        self.handle_one_request()

    def log_message(self, format, *args):  # noqa: A002 - the base class's name
        if getattr(self.server, "verbose", False):
            self.server.write_line(f"{self.address_string()} - - [{self.log_date_time_string()}] "
                                   f"{format % args}")

    # -- responses ------------------------------------------------------------------------
    def _send(self, status: int, body: bytes, ctype: str, *, cache: bool = False,
              headers: dict[str, str] | None = None) -> None:
        self.send_response(status)
        self.send_header("Content-Type", ctype)
        self.send_header("Content-Length", str(len(body)))
        self.send_header("Content-Security-Policy", CSP)
        self.send_header("X-Content-Type-Options", "nosniff")
        self.send_header("Referrer-Policy", "no-referrer")
        self.send_header("Cross-Origin-Opener-Policy", "same-origin")
        self.send_header("Cross-Origin-Resource-Policy", "same-origin")
        self.send_header("Cache-Control", "no-cache" if cache else "no-store")
        for k, v in (headers or {}).items():
            self.send_header(k, v)
        self.send_header("Connection", "close")
        self.end_headers()
        if self.command != "HEAD":
            self.wfile.write(body)

    def _json(self, status: int, obj: Any, headers: dict[str, str] | None = None) -> None:
        self._send(status, json.dumps(obj, allow_nan=False).encode(), "application/json",
                   headers=headers)

    def _error(self, status: int, message: str, headers: dict[str, str] | None = None) -> None:
        self._json(status, {"error": message}, headers)

    # -- who may ask ----------------------------------------------------------------------
    def _refusal(self, api: bool) -> str | None:
        """Why this request is refused (403), or None: Host, then Origin and
        Sec-Fetch-Site, then (for the API) the token. Nothing else is read before."""
        hosts = self.headers.get_all("Host") or []
        if len(hosts) != 1 or hosts[0].strip().lower() not in self.server.allowed_hosts:
            shown = ", ".join(h[:100] for h in hosts) or "(none)"
            return (f"Host {shown!r} is not served: only "
                    f"{', '.join(sorted(self.server.allowed_hosts))}")
        origins = self.headers.get_all("Origin") or []
        own = "http://" + hosts[0].strip().lower()
        if len(origins) > 1 or (origins and origins[0].strip().lower() != own):
            return f"cross-origin request refused (Origin {origins[0][:100]!r})"
        site = (self.headers.get("Sec-Fetch-Site") or "").strip().lower()
        if site not in ("", "same-origin", "none"):
            top_level = (self.headers.get("Sec-Fetch-Mode", "").lower() == "navigate"
                         and self.headers.get("Sec-Fetch-Dest", "").lower() == "document")
            if api or not top_level:
                return f"cross-site request refused (Sec-Fetch-Site: {site[:40]})"
        if api:
            tokens = self.headers.get_all(TOKEN_HEADER) or []
            if len(tokens) != 1 or not hmac.compare_digest(
                    tokens[0].strip().encode("utf-8", "replace"), self.server.token.encode()):
                return f"missing or wrong {TOKEN_HEADER} header (the page sends it)"
        return None

    # -- methods --------------------------------------------------------------------------
    def do_GET(self):  # noqa: N802 - http.server's name
        self.connection.settimeout(self.server.write_timeout_s)
        raw = self.path
        if len(raw) > _MAX_QUERY:
            return self._error(HTTPStatus.REQUEST_URI_TOO_LONG, "request too long")
        parts = urlsplit(raw)
        if parts.scheme or parts.netloc:
            return self._error(HTTPStatus.BAD_REQUEST, "absolute URLs are not served")
        path = parts.path
        why = self._refusal(api=path.startswith("/api/"))
        if why is not None:
            self.server.count("refused")
            return self._error(HTTPStatus.FORBIDDEN, why)
        if path.startswith("/api/"):
            return self._api(path, parts.query)
        # exact-name lookup: the request path is never joined onto a folder
        f = self.server.files.get(path)
        if f is None:
            return self._error(HTTPStatus.NOT_FOUND, f"not found: {path[:200]}")
        body = f.read_bytes()
        if f.name == "index.html":
            # the page: its token filled in, never cached (a new token per server start)
            return self._send(HTTPStatus.OK, body.replace(_TOKEN_META, self.server.token_meta),
                              _TYPES[f.suffix])
        self._send(HTTPStatus.OK, body, _TYPES[f.suffix], cache=True)

    do_HEAD = do_GET

    def _refuse(self):
        self.send_response(HTTPStatus.METHOD_NOT_ALLOWED)
        self.send_header("Allow", "GET, HEAD")
        self.send_header("Content-Length", "0")
        self.send_header("Connection", "close")
        self.end_headers()

    do_POST = do_PUT = do_DELETE = do_PATCH = do_OPTIONS = _refuse

    def _api(self, path: str, query: str) -> None:
        try:
            pairs = parse_qsl(query, keep_blank_values=True, strict_parsing=bool(query))
        except ValueError:
            return self._error(HTTPStatus.BAD_REQUEST, "malformed query string")
        keys = [k for k, _ in pairs]
        dup = sorted({k for k in keys if keys.count(k) > 1})
        if dup:
            return self._error(HTTPStatus.BAD_REQUEST,
                               f"parameter(s) given twice: {', '.join(dup)}")
        q = dict(pairs)
        try:
            if path == "/api/models":
                if q:
                    return self._error(HTTPStatus.BAD_REQUEST, "/api/models takes no parameters")
                return self._json(HTTPStatus.OK, self.server.models())
            if path == "/api/scene":
                return self._scene(q)
            if path == "/api/lut":
                return self._lut(q)
        except (ConnectionError, TimeoutError):
            raise
        except Exception as exc:  # a fault of the server: one line, no traceback to the client
            self.server.write_line(f"skydome view: internal error on {path}: "
                                   f"{type(exc).__name__}: {exc}")
            return self._error(HTTPStatus.INTERNAL_SERVER_ERROR,
                               f"internal error: {type(exc).__name__}")
        return self._error(HTTPStatus.NOT_FOUND, f"no API route {path[:200]}")

    def _scene(self, q: dict[str, str]) -> None:
        from skydome.viewer import scene

        try:
            model, _, _ = check_scene_request(q)
        except (ValueError, TypeError) as exc:
            return self._error(HTTPStatus.BAD_REQUEST, str(exc))
        bakes = self.server.bake_queue
        queued = model not in QUEUE_FREE_MODELS
        if queued:
            try:
                entered = bakes.enter(lambda: client_alive(self.connection))
            except QueueFull:
                return self._error(HTTPStatus.SERVICE_UNAVAILABLE,
                                   f"busy: a bake is running and {bakes.max_waiting} wait; "
                                   "try again", {"Retry-After": str(self.server.retry_after_s)})
            if not entered:
                self.server.note(f"client gone before its {model} bake: not baked")
                return None
        try:
            out = scene.shader_scene(q)
        except (ValueError, TypeError) as exc:
            return self._error(HTTPStatus.BAD_REQUEST, str(exc))
        finally:
            if queued:
                bakes.leave()
        if queued and not client_alive(self.connection):
            self.server.count("unsent")
            self.server.note(f"client gone during its {model} bake: answer not sent")
            return None
        return self._json(HTTPStatus.OK, out)

    def _lut(self, q: dict[str, str]) -> None:
        from skydome.viewer import scene

        extra = sorted(set(q) - {"key", "name"})
        if extra or "key" not in q or "name" not in q:
            return self._error(HTTPStatus.BAD_REQUEST, "/api/lut takes key and name")
        try:
            body = scene.lut_bytes(q["key"], q["name"])
        except (ValueError, KeyError) as exc:   # KeyError: the set was replaced meanwhile
            return self._error(HTTPStatus.BAD_REQUEST, str(exc))
        return self._send(HTTPStatus.OK, body, "application/octet-stream")


# -- the server ---------------------------------------------------------------------------
class ViewerServer(HTTPServer):
    """An HTTP server on a local address serving the viewer (see the module docstring
    for its rules). ``serve_forever`` accepts connections; a selector thread holds each
    until its first bytes arrive (or closes it after ``IDLE_TIMEOUT_S``), then one of
    ``WORKERS`` threads answers it."""

    allow_reuse_address = True
    #: listen backlog (a page's burst of module, shader and API requests fits many times)
    request_queue_size = LISTEN_BACKLOG = 128
    #: threads answering requests
    WORKERS = 32
    #: connections with a request waiting for a worker; beyond, 503 and closed
    READY_QUEUE = 256
    #: connections that have sent nothing yet; beyond, the oldest is closed
    MAX_IDLE = 512
    #: seconds a connection may stay silent before its first byte
    IDLE_TIMEOUT_S = 5.0
    #: seconds for the whole request head (request line and headers) once begun
    REQUEST_TIMEOUT_S = 5.0
    #: seconds to write an answer
    WRITE_TIMEOUT_S = 30.0
    #: requests that may wait for a running bake; beyond, 503
    BAKE_QUEUE = 4
    #: the Retry-After [s] of a 503
    RETRY_AFTER_S = 5

    def __init__(self, host: str = "127.0.0.1", port: int = 0, verbose: bool = False):
        check_host(host)
        if host == "::1":
            self.address_family = socket.AF_INET6
        if host == "localhost":
            host = "127.0.0.1"
        self.files = static_files()
        self.verbose = bool(verbose)
        self.token = secrets.token_urlsafe(32)
        self.token_meta = f'<meta name="skydome-token" content="{self.token}">'.encode()
        self.idle_timeout_s = self.IDLE_TIMEOUT_S
        self.request_timeout_s = self.REQUEST_TIMEOUT_S
        self.write_timeout_s = self.WRITE_TIMEOUT_S
        self.retry_after_s = self.RETRY_AFTER_S
        self.bake_queue = BakeQueue(self.BAKE_QUEUE)
        #: refused (403), idle connections closed, clients that dropped, connections turned
        #: away by a full worker queue, bakes finished for a client that had gone
        self.counts = {"refused": 0, "idle_closed": 0, "dropped": 0, "overloaded": 0,
                       "unsent": 0}
        self._count_lock = threading.Lock()
        self._log_lock = threading.Lock()
        self._models: dict | None = None
        super().__init__((host, port), _Handler)
        p = self.server_address[1]
        names = ("127.0.0.1", "localhost", "[::1]")
        self.allowed_hosts = frozenset(f"{n}:{p}" for n in names) | (
            frozenset(names) if p == 80 else frozenset())
        self._ready: queue.Queue = queue.Queue(self.READY_QUEUE)
        self._new: queue.SimpleQueue = queue.SimpleQueue()
        self._wake_r, self._wake_w = socket.socketpair()
        self._wake_r.setblocking(False)
        self._wake_w.setblocking(False)
        self._closing = False
        self._threads = [threading.Thread(target=self._waiter, name="viewer-idle", daemon=True)]
        self._threads += [threading.Thread(target=self._worker, name=f"viewer-{i}", daemon=True)
                          for i in range(self.WORKERS)]
        for t in self._threads:
            t.start()

    @property
    def url(self) -> str:
        host, port = self.server_address[:2]
        host = f"[{host}]" if ":" in host else host
        return f"http://{host}:{port}/"

    # -- bookkeeping ----------------------------------------------------------------------
    def count(self, what: str) -> None:
        with self._count_lock:
            self.counts[what] += 1

    def write_line(self, line: str) -> None:
        """``line`` on stderr, whole (one write under a lock: lines of several threads
        never interleave)."""
        with self._log_lock:
            with contextlib.suppress(OSError, ValueError):
                sys.stderr.write(line.replace("\n", " ") + "\n")
                sys.stderr.flush()

    def note(self, line: str) -> None:
        """One line on stderr, only with ``verbose``."""
        if self.verbose:
            self.write_line(f"skydome view: {line}")

    def handle_error(self, request, client_address):
        exc = sys.exc_info()[1]
        if isinstance(exc, (ConnectionError, TimeoutError)):
            self.count("dropped")
            self.note(f"client {client_address[0]}:{client_address[1]} dropped "
                      f"({type(exc).__name__})")
            return
        # not a client hanging up: one line, the traceback only with verbose
        self.write_line(f"skydome view: error answering {client_address[0]}:"
                        f"{client_address[1]}: {type(exc).__name__}: {exc}")
        if self.verbose:
            with self._log_lock:
                super().handle_error(request, client_address)

    # -- connections: idle ones in a selector, requests in a pool -------------------------
    def process_request(self, request, client_address):
        self._new.put((request, client_address))
        with contextlib.suppress(OSError):
            self._wake_w.send(b"\0")

    def _waiter(self):
        sel = selectors.DefaultSelector()
        sel.register(self._wake_r, selectors.EVENT_READ, None)
        idle: dict[socket.socket, tuple[float, Any]] = {}   # insertion order: oldest first

        def drop(sock, counted=True):
            sel.unregister(sock)
            del idle[sock]
            if counted:
                self.count("idle_closed")
            self.shutdown_request(sock)

        while not self._closing:
            timeout = None
            if idle:      # one timeout for all: the oldest is the first to expire
                timeout = max(0.0, next(iter(idle.values()))[0] - time.monotonic())
            for key, _ in sel.select(timeout):
                if key.fileobj is self._wake_r:
                    with contextlib.suppress(OSError):
                        while self._wake_r.recv(4096):
                            pass
                    continue
                sock = key.fileobj
                addr = idle[sock][1]
                sel.unregister(sock)
                del idle[sock]
                try:
                    self._ready.put_nowait((sock, addr))
                except queue.Full:
                    self.count("overloaded")
                    self._overloaded(sock)
            while True:
                try:
                    sock, addr = self._new.get_nowait()
                except queue.Empty:
                    break
                if len(idle) >= self.MAX_IDLE:
                    drop(next(iter(idle)))
                try:
                    sel.register(sock, selectors.EVENT_READ, None)
                except (OSError, ValueError):     # closed or reset meanwhile
                    self.shutdown_request(sock)
                    continue
                idle[sock] = (time.monotonic() + self.idle_timeout_s, addr)
            now = time.monotonic()
            while idle and next(iter(idle.values()))[0] <= now:
                drop(next(iter(idle)))
        for sock in list(idle):
            drop(sock, counted=False)
        sel.close()

    def _overloaded(self, sock):
        body = b'{"error": "overloaded: try again"}'
        head = (f"HTTP/1.1 503 Service Unavailable\r\nContent-Type: application/json\r\n"
                f"Content-Length: {len(body)}\r\nRetry-After: {self.retry_after_s}\r\n"
                "Connection: close\r\n\r\n").encode()
        with contextlib.suppress(OSError):
            sock.setblocking(False)
            sock.send(head + body)
        self.shutdown_request(sock)

    def _worker(self):
        while True:
            item = self._ready.get()
            if item is None:
                return
            request, client_address = item
            try:
                self.finish_request(request, client_address)
            except Exception:
                self.handle_error(request, client_address)
            finally:
                self.shutdown_request(request)

    def server_close(self):
        super().server_close()
        if self._closing:
            return
        self._closing = True
        with contextlib.suppress(OSError):
            self._wake_w.send(b"\0")
        for _ in range(self.WORKERS):
            self._ready.put(None)
        deadline = time.monotonic() + 5.0
        for t in self._threads:
            t.join(max(0.0, deadline - time.monotonic()))
        for s in (self._wake_r, self._wake_w):
            s.close()

    def models(self) -> dict:
        if self._models is None:
            from skydome.viewer.scene import VIEWER_MODELS, Dobashi2002View, viewer_class

            out = {}
            for name, keys in VIEWER_MODELS.items():
                cls = viewer_class(name)
                params = cls._parameters() if cls is Dobashi2002View else cls.parameters
                out[name] = {"reference": cls.reference, "summary": cls.summary, "parameters": [
                    {"name": p.name, "unit": p.unit, "default": p.default, "low": p.low,
                     "high": p.high, "kind": p.kind, "choices": list(p.choices), "doc": p.doc}
                    for p in params if p.name in keys]}
            self._models = out
        return self._models


def check_host(host: str) -> str:
    """Return ``host`` if it is a loopback name, else raise ValueError."""
    if host not in LOCAL_HOSTS:
        raise ValueError(f"host = {host!r} is not allowed: the viewer binds only to "
                         f"{', '.join(LOCAL_HOSTS)}")
    return host


def check_port(port) -> int:
    from skydome._validate import check_int

    return check_int("port", port, 0, 65535)


def make_server(host: str = "127.0.0.1", port: int = 0, verbose: bool = False) -> ViewerServer:
    """Validate and bind (port 0: any free port). The caller runs ``serve_forever`` (then
    ``shutdown`` and ``server_close``). ``verbose``: log every request, and one line for
    each client that hung up or timed out, on stderr (else nothing for those)."""
    check_host(host)
    check_port(port)
    return ViewerServer(host, port, verbose)


def serve(server: ViewerServer, on_ready=None) -> None:
    """Serve until SIGINT or SIGTERM, then shut down cleanly (socket closed, threads
    joined). Must run in the main thread (signal handlers)."""
    stop = threading.Event()

    def _stop(signum, frame):
        stop.set()

    old = {s: signal.signal(s, _stop) for s in (signal.SIGINT, signal.SIGTERM)}
    worker = threading.Thread(target=server.serve_forever, kwargs={"poll_interval": 0.1},
                              daemon=True)
    worker.start()
    try:
        if on_ready is not None:
            on_ready(server)
        while not stop.wait(0.2):
            pass
    finally:
        server.shutdown()
        worker.join()
        server.server_close()
        for s, h in old.items():
            signal.signal(s, h)
