"""Every ``qropt`` command the README and the docs/*.md pages show (each once, the README's first, then the
pages' in name order), run from a directory outside the repository (holding a copy of ``problems/``, which the
commands name): exit code 0, and every file the command names written and not empty (a folder it names: its
files). ``BY_EXECUTABLE``, the commands that use a shell (``&&``, ``>``) and those below run as subprocesses of
the installed executable; the others run the executable's function (``qropt.cli.main``) in a fresh process forked
from one that has imported qropt (``tests.child.run_cli``), without the start-up's second or so each. A command
that names a running Dask scheduler runs after the README's background lines (those ending in ``&``: the
scheduler and its workers) are started as the README shows them. ``qropt app`` serves until stopped: it runs
until it answers ``/api/health`` at the address it prints (no browser opened), then is stopped with Ctrl-C and
must exit 0. ``qropt bench`` and the ``python -m benchmarks`` lines are the benchmarks' own (minutes long, run
from the repository root): they are not run here."""

from __future__ import annotations

import contextlib
import os
import re
import shlex
import shutil
import signal
import socket
import subprocess
from pathlib import Path

import pytest
from distributed import Client

from tests.child import run_cli

ROOT = Path(__file__).resolve().parent.parent
OUTPUT_FLAGS = ("--plot", "--csv", "--animate", "--dxf", "--svg", "--save", "-o")


PAGES = [
    ROOT / "README.md",
    *sorted((ROOT / "docs").glob("*.md")),
    *sorted((ROOT / "docs" / "tutorials").glob("*.md")),
]


def shell_lines(page: Path) -> list[str]:
    return [line for block in re.findall(r"```sh\n(.*?)```", page.read_text(), re.S) for line in block.splitlines()]


def readme_commands(pages=None) -> list[str]:
    """The shell lines of the README and docs pages that start with ``qropt``, comments removed, each once."""
    out = []
    for page in PAGES if pages is None else pages:
        for line in shell_lines(page):
            command = re.sub(r"\s+#.*$", "", line).strip()
            if (command.startswith("qropt ") or command == "qropt") and command not in out:
                out.append(command)
    return out


def background_commands() -> list[str]:
    """The pages' shell lines that end in ``&`` (services the next commands use), without the ``&``."""
    lines = [line.strip() for page in PAGES for line in shell_lines(page)]
    return [re.sub(r"\s*&\s*(#.*)?$", "", line) for line in lines if re.search(r"&\s*(#.*)?$", line)]


def free_port() -> int:
    """A TCP port that nothing on this machine listens on now (the system's choice)."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def on_port(command: str, port: str, free: int) -> str:
    """The command with the page's port ``port`` (in --port N and host:N) replaced by ``free``."""
    return re.sub(rf"(--port |:){port}\b", rf"\g<1>{free}", command)


@contextlib.contextmanager
def services(cwd, address):
    """The README's background lines running (in their own process groups) until the scheduler at ``address``
    (tcp://host:port, the pages' port replaced by the caller with a free one) answers and has the workers they
    start; stopped afterwards."""
    bindir = Path(shutil.which("qropt")).parent
    env = {**os.environ, "PATH": f"{bindir}{os.pathsep}{os.environ['PATH']}"}
    port = address.rsplit(":", 1)[1]
    lines = background_commands()
    page_port = re.search(r"--port (\d+)", " ".join(lines)).group(1)
    procs = [
        subprocess.Popen(
            on_port(c, page_port, int(port)),
            shell=True,
            cwd=cwd,
            env=env,
            start_new_session=True,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
        )
        for c in lines
    ]
    try:
        workers = sum(int(n) for n in re.findall(r"--nworkers (\d+)", " ".join(lines)))
        with Client(address, timeout=60) as client:
            client.wait_for_workers(workers, timeout=120)
        yield
    finally:
        for p in procs:
            with contextlib.suppress(ProcessLookupError):
                os.killpg(p.pid, signal.SIGTERM)
        for p in procs:
            p.wait(timeout=30)


def outputs(command: str) -> list[str]:
    words = shlex.split(command.replace("&&", " ").replace(">", " > "))
    files = [words[i + 1] for i, w in enumerate(words[:-1]) if w in OUTPUT_FLAGS or w == ">"]
    return [f for f in files if f != "-"]


COMMANDS = readme_commands()
BY_EXECUTABLE = ("qropt --version", "qropt synth")  # the installed executable itself (the others: see the docstring)


def test_the_readme_shows_commands():
    assert len(COMMANDS) >= 10 and COMMANDS[0].startswith("qropt ")
    assert len(readme_commands([ROOT / "README.md"])) >= 3


@pytest.fixture(scope="module")
def workdir(tmp_path_factory):
    d = tmp_path_factory.mktemp("readme")
    shutil.copytree(ROOT / "problems", d / "problems")
    return d


@pytest.mark.parametrize("command", COMMANDS)
def test_readme_command_runs(command, workdir):
    exe = shutil.which("qropt")
    assert exe is not None, "qropt is not installed on PATH"
    shell = command.replace("qropt ", f"{shlex.quote(exe)} ") if command != "qropt" else exe
    if command.startswith("qropt bench"):
        pytest.skip("the benchmark suite runs from the repository root and takes minutes")
    if command.startswith("qropt app"):  # on a port the system picks (it prints the address)
        return _serves(re.sub(r"--port \d+", "--port 0", shell), workdir)
    address = re.search(r"--scheduler tcp://\S+:(\d+)", command)
    if address:  # the scheduler on a free port, not the page's
        shell = on_port(shell, address.group(1), free_port())
        address = re.search(r"--scheduler (tcp://\S+)", shell)
    if address or command in BY_EXECUTABLE or re.search(r"[&|<>;]", command):
        with services(workdir, address.group(1)) if address else contextlib.nullcontext():
            r = subprocess.run(shell, shell=True, cwd=workdir, capture_output=True, text=True, timeout=240)
        code, output = r.returncode, r.stdout + r.stderr
    else:
        code, output = run_cli(shlex.split(command)[1:], workdir, timeout=240)
    assert code == 0, (command, output[-3000:])
    for name in outputs(command):
        path = workdir / name
        if path.is_dir():  # a set of files (qropt project --count): every one written
            files = list(path.iterdir())
            assert files and all(f.stat().st_size > 0 for f in files), (command, name)
        else:
            assert path.is_file() and path.stat().st_size > 0, (command, name)


def _serves(shell: str, cwd) -> None:
    """Run a server command until it answers /api/health at the address it prints, then Ctrl-C it: exit 0."""
    import json
    import urllib.request

    env = {**os.environ, "BROWSER": "true"}  # webbrowser.open runs `true`: no browser here

    def ctrl_c_stops():  # as in a terminal (a shell's background job, and so pytest run as one, ignores SIGINT)
        signal.signal(signal.SIGINT, signal.SIG_DFL)

    p = subprocess.Popen(
        shlex.split(shell), cwd=cwd, env=env, stdout=subprocess.PIPE, text=True, preexec_fn=ctrl_c_stops
    )
    try:
        line = p.stdout.readline()
        url = re.search(r"http://\S+/", line)
        assert url, line
        with urllib.request.urlopen(url.group(0) + "api/health", timeout=30) as r:
            assert json.load(r)["status"] == "ok"
    finally:
        p.send_signal(signal.SIGINT)  # Ctrl-C
        code = p.wait(timeout=30)
    assert code == 0


SHOWN = re.compile(r"<!-- the (output|value) of (.+?) -->\n(?:```text\n(.*?)```|((?:\|[^\n]*\n)+))", re.S)


def shown_outputs() -> list[tuple]:
    """(page, 'output' or 'value', the command or Python expression, the text shown) for every block a page marks
    with ``<!-- the output of COMMAND -->`` (a ``qropt`` command's printout, in a text block) or ``<!-- the value of
    EXPRESSION -->`` (a Python expression's string, e.g. a Markdown table)."""
    return [
        (page.name, kind, what.strip(), block or table)
        for page in PAGES
        for kind, what, block, table in SHOWN.findall(page.read_text())
    ]


def test_the_pages_mark_their_shown_outputs():
    assert {page for page, *_ in shown_outputs()} >= {"README.md", "studies.md"}


@pytest.mark.parametrize("page, kind, what, text", shown_outputs(), ids=lambda v: str(v)[:40])
def test_a_shown_output_is_current(page, kind, what, text, workdir):
    if kind == "output":
        exe = shutil.which("qropt")
        r = subprocess.run(
            what.replace("qropt ", f"{shlex.quote(exe)} ", 1), shell=True, cwd=workdir, capture_output=True, text=True
        )
        assert r.returncode == 0, r.stderr[-2000:]
        got = r.stdout
    else:
        import qropt

        got = str(eval(what, {"qropt": qropt}))
    assert got.strip() == text.strip(), f"{page}: the shown {kind} of {what} is stale:\n{got}"
