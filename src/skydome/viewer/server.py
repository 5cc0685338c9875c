"""The viewer's local HTTP server (standard library only).

Why ``http.server``: the viewer serves a handful of static files and one small JSON API to
one local browser. :class:`http.server.ThreadingHTTPServer` does that without a new
dependency, and every rule below is a few explicit lines that the tests exercise:

* binds 127.0.0.1 (or ::1 / localhost) only; any other host is refused before a socket
  is opened;
* serves only the files listed in its own ``static/`` folder, by exact name: no path is
  ever joined from the request, so ``..``, encoded (``%2e%2e``, ``%2f``), doubled
  (``%252e``), backslash and absolute paths, and symlinks out of the folder cannot reach
  anything else (they are 404);
* ``GET /api/models`` lists the models and their parameters; ``GET /api/scene?model=...``
  returns the shader's numbers (:func:`skydome.viewer.scene.shader_scene`);
  ``GET /api/lut?key=...&name=...`` one baked table as raw float32; bad
  parameters give 400 with ``{"error": message}``, the CLI's message;
* every response carries a strict Content-Security-Policy (same origin only, no inline
  script, no external resources), ``X-Content-Type-Options: nosniff``, no caching of the
  API, and ``Referrer-Policy: no-referrer``; only GET and HEAD are allowed.
"""

from __future__ import annotations

import json
import signal
import threading
from http import HTTPStatus
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from importlib import resources
from pathlib import Path
from typing import Any
from urllib.parse import parse_qsl, urlsplit

__all__ = ["LOCAL_HOSTS", "CSP", "ViewerServer", "make_server", "serve", "static_files"]

#: Host names the server may bind to.
LOCAL_HOSTS = ("127.0.0.1", "::1", "localhost")

#: Content-Security-Policy of every response.
CSP = ("default-src 'none'; script-src 'self'; style-src 'self'; img-src 'self' data: blob:; "
       "connect-src 'self'; base-uri 'none'; form-action 'none'; frame-ancestors 'none'")

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


class _Handler(BaseHTTPRequestHandler):
    server_version = "skydome-viewer"
    sys_version = ""
    protocol_version = "HTTP/1.1"

    def log_message(self, format, *args):  # noqa: A002 - the base class's name
        if getattr(self.server, "verbose", False):
            super().log_message(format, *args)

    # -- responses ------------------------------------------------------------------------
    def _send(self, status: int, body: bytes, ctype: str, *, cache: bool = False) -> None:
        self.send_response(status)
        self.send_header("Content-Type", ctype)
        self.send_header("Content-Length", str(len(body)))
        self.send_header("Content-Security-Policy", CSP)
        self.send_header("X-Content-Type-Options", "nosniff")
        self.send_header("Referrer-Policy", "no-referrer")
        self.send_header("Cross-Origin-Opener-Policy", "same-origin")
        self.send_header("Cache-Control", "no-cache" if cache else "no-store")
        self.end_headers()
        if self.command != "HEAD":
            self.wfile.write(body)

    def _json(self, status: int, obj: Any) -> None:
        self._send(status, json.dumps(obj, allow_nan=False).encode(), "application/json")

    def _error(self, status: int, message: str) -> None:
        self._json(status, {"error": message})

    # -- methods --------------------------------------------------------------------------
    def do_GET(self):  # noqa: N802 - http.server's name
        raw = self.path
        if len(raw) > _MAX_QUERY:
            return self._error(HTTPStatus.REQUEST_URI_TOO_LONG, "request too long")
        parts = urlsplit(raw)
        if parts.scheme or parts.netloc:
            return self._error(HTTPStatus.BAD_REQUEST, "absolute URLs are not served")
        path = parts.path
        if path.startswith("/api/"):
            return self._api(path, parts.query)
        # exact-name lookup: the request path is never joined onto a folder
        f = self.server.files.get(path)
        if f is None:
            return self._error(HTTPStatus.NOT_FOUND, f"not found: {path[:200]}")
        self._send(HTTPStatus.OK, f.read_bytes(), _TYPES[f.suffix], cache=True)

    do_HEAD = do_GET

    def _refuse(self):
        self.send_response(HTTPStatus.METHOD_NOT_ALLOWED)
        self.send_header("Allow", "GET, HEAD")
        self.send_header("Content-Length", "0")
        self.end_headers()

    do_POST = do_PUT = do_DELETE = do_PATCH = do_OPTIONS = _refuse

    def _api(self, path: str, query: str) -> None:
        from skydome.viewer import scene

        try:
            pairs = parse_qsl(query, keep_blank_values=True, strict_parsing=bool(query))
        except ValueError:
            return self._error(HTTPStatus.BAD_REQUEST, "malformed query string")
        keys = [k for k, _ in pairs]
        dup = sorted({k for k in keys if keys.count(k) > 1})
        if dup:
            return self._error(HTTPStatus.BAD_REQUEST, f"parameter(s) given twice: {', '.join(dup)}")
        q = dict(pairs)
        if path == "/api/models":
            if q:
                return self._error(HTTPStatus.BAD_REQUEST, "/api/models takes no parameters")
            return self._json(HTTPStatus.OK, self.server.models())
        if path == "/api/scene":
            try:
                out = scene.shader_scene(q)
            except (ValueError, TypeError) as exc:
                return self._error(HTTPStatus.BAD_REQUEST, str(exc))
            return self._json(HTTPStatus.OK, out)
        if path == "/api/lut":
            extra = sorted(set(q) - {"key", "name"})
            if extra or "key" not in q or "name" not in q:
                return self._error(HTTPStatus.BAD_REQUEST, "/api/lut takes key and name")
            try:
                body = scene.lut_bytes(q["key"], q["name"])
            except ValueError as exc:
                return self._error(HTTPStatus.BAD_REQUEST, str(exc))
            return self._send(HTTPStatus.OK, body, "application/octet-stream")
        return self._error(HTTPStatus.NOT_FOUND, f"no API route {path[:200]}")


class ViewerServer(ThreadingHTTPServer):
    """A :class:`ThreadingHTTPServer` on a local address serving the viewer."""

    daemon_threads = True
    allow_reuse_address = True

    def __init__(self, host: str = "127.0.0.1", port: int = 0, verbose: bool = False):
        check_host(host)
        if host == "::1":
            import socket

            self.address_family = socket.AF_INET6
        if host == "localhost":
            host = "127.0.0.1"
        self.files = static_files()
        self.verbose = verbose
        self._models: dict | None = None
        super().__init__((host, port), _Handler)

    @property
    def url(self) -> str:
        host, port = self.server_address[:2]
        host = f"[{host}]" if ":" in host else host
        return f"http://{host}:{port}/"

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
    """Validate and bind (port 0: any free port). The caller runs ``serve_forever``."""
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
