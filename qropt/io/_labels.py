"""Where the joints' names go on a picture of a mechanism: beside each joint, off the other names, markers, links
and blocks (``place_labels``). Plain geometry in one length unit with y up; ``qropt.io.plots.draw_shapes`` (every
matplotlib picture) and ``qropt.io.notebook.mechanism_svg`` place their names with it."""

from __future__ import annotations

import math

import numpy as np

LABEL_DIRECTIONS = tuple((math.cos(math.radians(a)), math.sin(math.radians(a))) for a in range(45, 405, 45))  # NE first
# what a name over a shape's outline costs (by the shape's part, ``qropt.io.drawing.Shape``), relative to a link
LINE_WEIGHTS = {"link": 1.0, "plate": 1.0, "slot": 0.5, "block": 0.5, "ram": 0.5, "slide": 0.1, "path": 0.1}
SOLIDS = ("block", "ram", "plate")  # parts a name over would hide


def align(u) -> tuple[str, str]:
    """The (horizontal, vertical) alignment of a label set off in direction u from its anchor: its near corner or
    edge at the anchor ('left', 'right' or 'center'; 'bottom', 'top' or 'center')."""
    return ("left" if u[0] > 0.3 else "right" if u[0] < -0.3 else "center"), (
        "bottom" if u[1] > 0.3 else "top" if u[1] < -0.3 else "center"
    )


def place_labels(points, sizes, radii, gaps, lines=(), solids=(), frame=None, taken=()) -> list:
    """Where each joint's label goes, all in one length unit with y up (pixels where it is called): points (n, 2)
    the joints, sizes (n, 2) each label's width and height, radii (n,) each joint marker's radius, gaps: the gaps
    tried between a marker and its label, nearest first; lines: (polyline (k, 2), weight) a label should not cover;
    solids: polygons ((k, 2)) a label would hide (a joint inside one is labelled outside it); frame (x0, y0, x1,
    y1): where labels should stay; taken: boxes (x0, y0, x1, y1) of what else is written there (other texts, a
    legend), kept off as the other labels are.

    A label's box touches the circle of radius (marker or surrounding solid) + gap about its joint at one of the 8
    LABEL_DIRECTIONS (its corner on a diagonal, its edge's middle otherwise). Its cost: overlapping another label,
    a taken box or a marker (forbidden in effect), leaving the frame, covering lines and solids, then its distance.
    Margins are fractions of the label's height: a fifth from other labels and taken boxes, a tenth from markers and
    lines. Labels are placed in order, each at its cheapest box, then each once more given all the others (the same
    input, the same places). Returns for each joint (direction (ux, uy), distance from the joint to the box, box (x0,
    y0, x1, y1))."""
    pts = np.asarray(points, float).reshape(-1, 2)
    sizes = np.asarray(sizes, float).reshape(-1, 2)
    radii = np.asarray(radii, float).reshape(-1)
    gaps = np.asarray(gaps, float).reshape(-1)
    dirs = np.array(LABEL_DIRECTIONS)
    segs, weights = [np.zeros((0, 4))], [np.zeros(0)]
    for poly, w in lines:
        p = np.asarray(poly, float).reshape(-1, 2)
        segs.append(np.c_[p[:-1], p[1:]])
        weights.append(np.full(len(p) - 1, float(w)))
    segs, weights = np.concatenate(segs), np.concatenate(weights)
    polys = [np.asarray(s, float).reshape(-1, 2) for s in solids]
    u = np.repeat(dirs, len(gaps), axis=0)  # the candidates: each direction at each gap
    rank = np.repeat(np.arange(len(dirs)), len(gaps)) * 0.01 + np.tile(np.arange(len(gaps)), len(dirs)) * 0.5
    candidates = []  # per joint: cost without the other labels, distance, boxes (k, 4), boxes with a margin
    for i, (p, (w, h)) in enumerate(zip(pts, sizes, strict=True)):
        unit = max(h, 1e-9)
        d = np.hypot(*(pts - p).T)
        clear = max(radii[i], float(radii[d <= radii].max(initial=0.0)))
        inside = [q for q in polys if _inside(p[None], q)[0]]
        start = np.array([max([clear] + [_exit(p, v, q) for q in inside]) for v in dirs])
        r = np.repeat(start, len(gaps)) + np.tile(gaps, len(dirs))
        at = p + r[:, None] * u
        x0 = at[:, 0] - np.where(u[:, 0] > 0.3, 0.0, np.where(u[:, 0] < -0.3, w, w / 2))  # aligned as ``align``
        y0 = at[:, 1] - np.where(u[:, 1] > 0.3, 0.0, np.where(u[:, 1] < -0.3, h, h / 2))
        boxes = np.c_[x0, y0, x0 + w, y0 + h]
        cost = rank + 0.15 * r / unit
        gx = np.maximum(np.maximum(boxes[:, None, 0] - pts[:, 0], pts[:, 0] - boxes[:, None, 2]), 0.0)
        gy = np.maximum(np.maximum(boxes[:, None, 1] - pts[:, 1], pts[:, 1] - boxes[:, None, 3]), 0.0)
        under = (np.hypot(gx, gy) < radii + 0.1 * unit) & (d > 1e-9)  # another joint's marker under the label
        cost += 1000.0 * under.sum(axis=1)
        if frame is not None:
            f = np.asarray(frame, float)
            out = np.maximum(f[:2] - boxes[:, :2], 0.0).sum(axis=1) + np.maximum(boxes[:, 2:] - f[2:], 0.0).sum(axis=1)
            cost += 100.0 * (out > 0) + 10.0 * out / unit
        cost += 10.0 * (np.nan_to_num(_clipped(segs, boxes + 0.1 * unit * np.array([-1, -1, 1, 1]))) @ weights) / unit
        grid = np.linspace(0.0, 1.0, 3)
        samples = np.stack(  # nine points of each box: corners, middles of the edges, centre
            [boxes[:, 0, None] + np.repeat(grid, 3) * w, boxes[:, 1, None] + np.tile(grid, 3) * h], axis=-1
        ).reshape(-1, 2)
        for q in polys:
            cost += 8.0 * _inside(samples, q).reshape(len(boxes), -1).mean(axis=1)
        candidates.append((cost, r, boxes, boxes + 0.2 * unit * np.array([-1, -1, 1, 1])))
    chosen: list = [None] * len(pts)
    for _ in range(2):
        for i, (cost, r, boxes, apart) in enumerate(candidates):
            total = cost.copy()
            others = [c[2] for j, c in enumerate(chosen) if j != i and c is not None]
            for b in [*others, *taken]:
                shared = _overlap(boxes, b)
                total += np.where(_overlap(apart, b) > 0, 1000.0 + shared, 0.0)
            k = int(np.argmin(total))
            chosen[i] = (tuple(u[k]), float(r[k]), tuple(map(float, boxes[k])))
    return chosen


def _overlap(boxes, b) -> np.ndarray:
    """The area each of boxes (k, 4: x0, y0, x1, y1) shares with box b."""
    wx = np.minimum(boxes[:, 2], b[2]) - np.maximum(boxes[:, 0], b[0])
    wy = np.minimum(boxes[:, 3], b[3]) - np.maximum(boxes[:, 1], b[1])
    return np.maximum(wx, 0.0) * np.maximum(wy, 0.0)


def _clipped(segs, boxes) -> np.ndarray:
    """(k, m): the length of each segment (m, 4: x0, y0, x1, y1) inside each box (k, 4) (Liang-Barsky)."""
    a, d = segs[None, :, :2], segs[None, :, 2:] - segs[None, :, :2]
    lo, hi = np.zeros((len(boxes), len(segs))), np.ones((len(boxes), len(segs)))
    with np.errstate(divide="ignore", invalid="ignore"):
        for k in range(2):
            low, high = boxes[:, k, None], boxes[:, k + 2, None]
            t0, t1 = (low - a[..., k]) / d[..., k], (high - a[..., k]) / d[..., k]
            flat = d[..., k] == 0
            within = (a[..., k] >= low) & (a[..., k] <= high)
            lo = np.where(flat, np.where(within, lo, 1.0), np.maximum(lo, np.minimum(t0, t1)))
            hi = np.where(flat, np.where(within, hi, 0.0), np.minimum(hi, np.maximum(t0, t1)))
    return np.maximum(hi - lo, 0.0) * np.hypot(d[..., 0], d[..., 1])


def _exit(p, u, poly) -> float:
    """How far from p along the unit vector u the polygon's farthest edge ahead is (0 if none is ahead)."""
    e = np.roll(poly, -1, axis=0) - poly
    q = poly - p
    den = u[0] * -e[:, 1] + u[1] * e[:, 0]  # p + t u = a + s e for each edge a -> a + e
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (q[:, 0] * -e[:, 1] + q[:, 1] * e[:, 0]) / den
        s = (u[0] * q[:, 1] - u[1] * q[:, 0]) / den
    ahead = (np.abs(den) > 1e-12) & (t > 0) & (s >= -1e-9) & (s <= 1 + 1e-9)
    return float(t[ahead].max(initial=0.0))


def _inside(points, poly) -> np.ndarray:
    """Whether each point (m, 2) is inside the polygon (k, 2) (even-odd rule)."""
    x, y = points[:, :1], points[:, 1:]
    a, b = poly, np.roll(poly, -1, axis=0)
    crosses = (a[:, 1] > y) != (b[:, 1] > y)
    with np.errstate(divide="ignore", invalid="ignore"):
        at = a[:, 0] + (y - a[:, 1]) * (b[:, 0] - a[:, 0]) / (b[:, 1] - a[:, 1])
    return (crosses & (x < at)).sum(axis=1) % 2 == 1


__all__ = ["LABEL_DIRECTIONS", "LINE_WEIGHTS", "SOLIDS", "align", "place_labels"]
