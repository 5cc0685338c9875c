"""``skydome view``: start the viewer's local server and open the page."""

from __future__ import annotations

import sys

import typer

def view(port: int = typer.Option(0, help="port on 127.0.0.1 (0: any free port)"),
         host: str = typer.Option("127.0.0.1", help="loopback address to bind: 127.0.0.1, ::1 or localhost"),
         no_browser: bool = typer.Option(False, "--no-browser", help="do not open a browser"),
         verbose: bool = typer.Option(False, "--verbose",
                                      help="log every request, and one line per client that "
                                           "hung up or timed out, on stderr")):
    """Render the sky live in the browser (WebGL2): prints the page's URL and serves it
    until Ctrl-C."""
    from skydome.viewer.server import make_server, serve

    try:
        server = make_server(host, port, verbose)
    except (ValueError, TypeError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        raise typer.Exit(2) from None
    except OSError as exc:
        print(f"error: cannot listen on {host}:{port}: {exc.strerror or exc}", file=sys.stderr)
        raise typer.Exit(2) from None

    def ready(srv):
        print(srv.url, flush=True)
        if not no_browser:
            import webbrowser

            try:
                webbrowser.open(srv.url)
            except Exception:  # no browser here: the URL is printed
                pass

    serve(server, ready)
