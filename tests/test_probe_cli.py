"""The command line's own hostile-probe cases: a problem file that exits, the global --quiet before bench, and
every objective the criteria define offered to synth."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

from qropt import cli
from qropt.synthesis import criteria

ROOT = Path(__file__).resolve().parent.parent


def run(*args, cwd=ROOT):
    code = "import sys; from qropt.cli import main; sys.exit(main(sys.argv[1:]))"
    return subprocess.run([sys.executable, "-c", code, *args], capture_output=True, text=True, timeout=300, cwd=cwd)


def test_a_problem_file_that_exits_is_one_error_line(tmp_path):
    f = tmp_path / "exits.py"
    f.write_text("import sys\n\n\ndef build():\n    sys.exit(0)\n")
    r = run("synth", str(f))
    assert r.returncode != 0 and r.stdout == ""
    assert r.stderr.count("\n") == 1 and "does not load: SystemExit" in r.stderr and "Traceback" not in r.stderr


def test_the_global_quiet_flag_may_precede_bench():
    r = run("--quiet", "bench", "--help")
    assert r.returncode == 0 and "--repeat" in r.stdout and "unrecognized" not in r.stderr


def test_synth_offers_every_objective_of_the_criteria(capsys):
    commands = cli.parser()._subparsers._group_actions[0].choices
    choices = {a.dest: a for a in commands["synth"]._actions}["objective"].choices
    assert set(choices) == {o for o in criteria.objectives() if o} | {"none"}
    code = cli.main(
        ["synth", str(ROOT / "problems" / "slider_crank_gamma.py"), "--objective", "min_peak_velocity", "--json"]
    )
    out = json.loads(capsys.readouterr().out)
    assert code == 0 and out["status"] == "optimal" and out["objective"] == out["quantities"]["peak_velocity"]
