"""``qropt app``: the web application on this machine (127.0.0.1 unless --host says otherwise: a problem file is
code, and so is the app that runs it)."""

from __future__ import annotations

import threading
import webbrowser

COMMAND = "app"
HELP = "the web application: design, mechanism and synthesis pages in the browser (qropt[app])"
EXAMPLES = ("qropt app --no-browser --port 8765", "qropt app problems/user_slotted_lever.py --no-browser")


def add_arguments(p) -> None:
    p.add_argument("problems", nargs="*", metavar="PROBLEM", help="problem files whose types and tasks it serves")
    p.add_argument("--port", type=int, default=8050, help="port (default 8050; 0: any free port)")
    p.add_argument("--host", default="127.0.0.1", help="address to listen on (default 127.0.0.1: this machine only)")
    p.add_argument("--no-browser", action="store_true", help="do not open the browser")
    p.add_argument("--workers", type=int, default=1, help="solver processes (default 1)")
    p.add_argument("--time-limit", type=float, default=300.0, help="seconds a solve or design may take (300)")


def run(args) -> int:
    from qropt.cli import CliError

    if not 0 <= args.port <= 65535:
        raise CliError(f"--port is 0 to 65535, got {args.port}")
    if not 1 <= args.workers <= 16:
        raise CliError(f"--workers is 1 to 16, got {args.workers}")
    if not 1 <= args.time_limit <= 86400:
        raise CliError(f"--time-limit is 1 to 86400 s, got {args.time_limit:g}")
    try:
        from werkzeug.serving import make_server

        from qropt.app import create_app
    except ImportError as e:
        raise CliError(f'the app needs its extra: pip install "qropt[app]" ({e})') from None
    import logging

    logging.getLogger("werkzeug").setLevel(logging.WARNING)  # errors only, not a line per request
    app = create_app(args.problems, workers=args.workers, time_limit=args.time_limit)
    try:
        server = make_server(args.host, args.port, app, threaded=True)
    except OSError as e:
        app.extensions["qropt_jobs"].close()
        raise CliError(f"cannot listen on {args.host}:{args.port}: {e.strerror or e}") from None
    url = f"http://{args.host}:{server.server_port}/"
    print(f"qropt app at {url} (Ctrl-C stops it)", flush=True)
    if not args.no_browser:
        threading.Timer(0.5, webbrowser.open, (url,)).start()
    try:
        server.serve_forever()
    except KeyboardInterrupt:
        pass
    finally:
        app.extensions["qropt_jobs"].close()
    return 0
