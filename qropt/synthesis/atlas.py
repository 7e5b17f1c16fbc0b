"""The atlas: the best designs of a problem's shape, found once at time-ratio nodes by a search far larger than a
solve's, and the starts they give a solve between the nodes.

A problem whose targets are a time ratio and a stroke, whose bounds scale with the stroke and whose objective
depends on the shape alone (gamma_min, a size, the peak acceleration or velocity) has optima whose shape depends
on the time ratio alone: at stroke s every length is s times its value at stroke 1, and TR, gamma_min and the
shape of the motion change with neither s nor omega2. ``signature`` is that shape of a problem (lengths in
strokes, no targets, no name, no omega2). The atlas (``atlas.json`` beside this module, written by ``python -m
benchmarks.atlas``) holds, per signature, node time ratios and at each node the best distinct certified designs
of a many-start search, continued from node to node, lengths in strokes. A solve of a problem whose signature
is in the atlas, at a TR inside its nodes, first starts from the designs of the two nodes around it
(``starts``); only where none of them gives a certified design does it run the multi-start. A problem whose
signature is in the atlas only without its bound conditions starts from that problem's designs.
"""

from __future__ import annotations

import bisect
import dataclasses
import functools
import json
from dataclasses import dataclass
from pathlib import Path

from qropt.synthesis import criteria, scaling

PATH = Path(__file__).with_name("atlas.json")
SHAPE_CONDITIONS = ("grashof", criteria.GammaMin.name)  # conditions that do not change with the scale
SAME = 0.02  # a node's designs this close in every parameter (strokes for lengths and offsets, rad for angles) are
# one start: a solve from the second ends where the first's does
SAME_SHAPE = ("mechanism", "fixed", "free", "branches")  # what a problem shares with the atlas entries ``related``
# gives it


def _round(x: float) -> float:
    return float(f"{x:.9g}")  # scaled problems' bounds agree to rounding


def _shape(problem) -> dict:
    """The problem's shape: its mechanism, fixed values and bounds (lengths in strokes), branches and what it
    asks for (conditions, objective, size, accel_over)."""
    s = float(problem.targets["stroke"])

    def rel(k, v):
        return _round(v / s if scaling.scales(problem, k) else v)

    d = problem.to_dict()
    return {
        "mechanism": d["mechanism"],
        "fixed": {k: rel(k, v) for k, v in d["fixed"].items()},
        "free": {k: [rel(k, lo), rel(k, hi)] for k, (lo, hi) in d["free"].items()},
        "conditions": d["conditions"],
        "objective": d["objective"],
        "size": d["size"],
        "accel_over": d["accel_over"],
        "branches": d["branches"],
    }


def _criterion(problem):
    """The objective's criterion of a problem whose targets are a TR and a stroke; None otherwise."""
    if set(problem.targets) != {"time_ratio", "stroke"} or not problem.objective:
        return None
    return criteria.of_problem(problem)


def signature(problem) -> str | None:
    """The problem's shape as a key (JSON text): None where its optima do not scale with its stroke (other targets,
    a dynamic objective, or a condition with a length in it)."""
    c = _criterion(problem)
    if c is None or not (c.kinematic or c.size) or set(problem.conditions) - set(SHAPE_CONDITIONS):
        return None
    return json.dumps(_shape(problem), sort_keys=True)


@dataclass(frozen=True)
class Starts:
    """A solve's starts from the atlas: (free values, branch) pairs in the problem's lengths, the node (0 or 1,
    the lower or upper time ratio) each comes from, what they are, the nodes' time ratios (``trs``), and the bound
    conditions of the problem they were found without (``unbounded``)."""

    designs: tuple = ()
    how: str = ""
    nodes: tuple = ()
    trs: tuple = ()
    unbounded: tuple = ()  # the problem's bound conditions the designs were found without (``starts``)


@functools.cache
def _entries() -> dict:
    try:
        data = json.loads(PATH.read_text())
    except FileNotFoundError:
        return {}
    return {e["signature"]: e for e in data["entries"]}


def _same(a: dict, b: dict) -> bool:
    """Whether two designs of a node are one start: the same branch and every parameter within SAME."""
    return a["branch"] == b["branch"] and all(abs(x - b["params"][k]) < SAME for k, x in a["params"].items())


def starts(problem) -> Starts:
    """The atlas's designs at the nodes around the problem's time ratio, scaled to its stroke and clipped to its
    bounds; where the atlas holds the problem only without its bound conditions, the designs of that problem
    (``unbounded`` names the bounds: where its optimum meets them, it is the problem's); empty where neither is in
    the atlas or the TR is outside the nodes."""
    key = signature(problem)
    entry = _entries().get(key) if key else None
    if entry is not None:
        return _around(problem, [entry])
    loose = [k for k in problem.conditions if k in criteria.bounds()]
    if not loose:
        return Starts()
    key = signature(unbounded(problem, loose))
    entry = _entries().get(key) if key else None
    if entry is None:
        return Starts()
    found = _around(problem, [entry], f" without its bound {' and '.join(loose)}")
    return dataclasses.replace(found, unbounded=tuple(loose)) if found.designs else found


def unbounded(problem, names):
    """The problem without the bound conditions ``names``."""
    if not names:
        return problem
    return problem.replace(conditions={k: v for k, v in problem.conditions.items() if k not in names})


def related(problem) -> Starts:
    """Where a problem's optima do not scale with its stroke (a dynamic objective): the atlas's designs of the same
    mechanism, fixed values, bounds and branches by every objective the atlas holds for them (optima by the
    transmission angle and the acceleration), as ``starts`` gives them; empty where the objective is kinematic or
    a size, the targets are not a TR and a stroke, or the atlas holds none."""
    c = _criterion(problem)
    if c is None or c.kinematic or c.size:
        return Starts()
    entries = _by_shape().get(_shared(_shape(problem)), [])
    return _around(problem, entries) if entries else Starts()


def _shared(shape: dict) -> str:
    return json.dumps({k: shape[k] for k in SAME_SHAPE}, sort_keys=True)


@functools.cache
def _by_shape() -> dict:
    """The atlas's entries by what they share with a problem that ``related`` serves (``SAME_SHAPE``)."""
    out: dict = {}
    for key, e in _entries().items():
        out.setdefault(_shared(json.loads(key)), []).append(e)
    return out


def _around(problem, entries: list, without: str = "") -> Starts:
    """The designs of entries (with the same nodes) at the nodes around the problem's TR (``starts``); without:
    words after the objective, for designs found without the problem's bounds."""
    tr, nodes = float(problem.targets["time_ratio"]), entries[0]["nodes"]
    if not nodes[0] <= tr <= nodes[-1]:
        return Starts()
    i = max(bisect.bisect_right(nodes, tr) - 1, 0)
    around = sorted({i, min(i + 1, len(nodes) - 1)})
    s = float(problem.targets["stroke"])
    out, node = [], []
    for entry in entries:
        for n, j in enumerate(around):
            kept = []
            for d in entry["designs"][j]:
                if any(_same(d, e) for e in kept):
                    continue
                kept.append(d)
                v = {k: x * s if scaling.scales(problem, k) else x for k, x in d["params"].items()}
                v = {k: min(max(v[k], lo), hi) for k, (lo, hi) in problem.free.items()}
                out.append((v, {k: float(b) for k, b in d["branch"].items()}))
                node.append(n)
    at = " and ".join(f"{nodes[j]:g}" for j in around)
    by = " and ".join(e["objective"] for e in entries)
    how = f"{len(out)} designs of the atlas at TR {at} by {by}{without}"
    how += f" (each node's best of a {entries[0]['starts']}-start"
    how += f" search, of the best of {entries[0]['shapes']:,} random shapes near it" if entries[0].get("shapes") else ""
    how += " and of solves from its neighbours' designs)"
    return Starts(tuple(out), how, tuple(node), tuple(float(nodes[j]) for j in around))


__all__ = ["signature", "starts", "related", "unbounded", "Starts", "PATH"]
