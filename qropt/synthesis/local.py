"""The local solve: one start -> one certified (or refused) candidate.

A backend run (IPOPT by default) on the problem's Formulation, then an exchange loop: the exact evaluation of
the design names the crank angles where it disagrees with the NLP's samples, they become sample angles, and the
NLP is solved again from where it stopped. ``polish`` is Newton on the target and dead-centre equations from a
closed-form point of a square problem.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from qropt.errors import QroptError
from qropt.synthesis import criteria, newton
from qropt.synthesis import starts as starts_
from qropt.synthesis.backends import CONVERGED, Status
from qropt.synthesis.certificate import Designs, certify, residuals, target_values
from qropt.synthesis.formulation import TWO_PI, Formulation, coarse_nodes
from qropt.synthesis.settings import DEFAULT

MEMO = 64  # problems a solver keeps derived problems of (a chart's tiles bring thousands)


@dataclass
class Candidate:
    """One local solve's outcome: the design, its certificate data and the backend's statistics."""

    ok: bool
    values: dict
    branch: dict
    orientation: int
    mechanism: object = None
    info: dict = field(default_factory=dict)
    residuals: dict = field(default_factory=dict)
    statuses: list = field(default_factory=list)  # the backend's own word for each run
    ends: list = field(default_factory=list)  # each run's Status
    iterations: int = 0
    t_ipopt: float = 0.0
    rounds: int = 0
    origin: str = ""  # the strategy's word for its start ('atlas', 'multistart', 'guard', 'wrapped', ...)
    start: int = -1  # the index of its start in a MultiStart.run's list
    parent: object = None  # the candidate it was continued or solved again from (a guarded or wrapped design)
    q: dict | None = None
    pruned: bool = False
    problem: object = None  # the problem as the design fixes it (a free counterweight chosen); None: the solve's
    hint: object = None  # a certified optimum's NLP point and multipliers, for a continuation (``newton.Hint``)

    @property
    def converged(self) -> bool:
        return bool(self.ends) and self.ends[-1] in CONVERGED

    def residuals_over(self, tol: float) -> bool:
        return max(self.residuals.values(), default=0.0) > tol

    @property
    def cost(self) -> float:
        """Its IPOPT time, s (its ``iterations`` counted beside it)."""
        return self.t_ipopt


def _dynamic_key(problem) -> tuple[tuple, tuple | None]:
    """What a criterion bakes into its NLP (any one what its ``baked`` says; a dynamic one also the masses, the loads
    and omega2), and the dynamic task the NLP belongs to: that key where a criterion needs masses (whatever the
    objective), else None."""
    used = criteria.used(problem)
    baked = tuple(b for c in used for b in c.baked(problem))
    if not any(c.needs_masses for c in used):
        return baked, None
    key = (repr(problem.masses), repr(problem.loads), problem.omega2, *baked)
    return key, key


class Formulations:
    """The NLPs of a Solver, one per problem structure, built on first use (immutable; numbers are passed). A
    dynamic NLP bakes its masses, loads and omega2 in: those of the KEPT_TASKS dynamic tasks used last are kept,
    an older task's dropped (each such NLP holds tens of megabytes; a process that designs under many loads would
    otherwise hold them all)."""

    KEPT_TASKS = 2  # two load cases compared in turn

    def __init__(self, samples: int, extra: int):
        self.samples, self.extra, self._built = samples, extra, {}
        self._tasks: dict = {}  # dynamic task -> the keys of its NLPs, the least recently used first

    def __len__(self):
        return len(self._built)

    def get(
        self, problem, branch: dict, orientation: int, range_target=None, sense=1, guarded=None, coarse=0
    ) -> Formulation:
        """guarded: with the rows that keep the output's reversals at its dead centres (default: unless its type
        reverses once a turn by construction, ``Mechanism.SYNTHESIS.one_reversal``); coarse: its quadratures on
        a rule of that many nodes a stroke, where it states one (``Criterion.coarse``) and the rule is coarser
        than the certifier's (0: the certifier's)."""
        guarded = not problem.mechanism.SYNTHESIS.one_reversal if guarded is None else guarded
        coarse = coarse_nodes(problem, coarse, range_target)
        c = problem.conditions
        bounds = tuple(k for k in c if k not in ("grashof", "linear", "ratio"))
        cond = (c.get("grashof"), bounds, repr(c.get("linear")), repr(c.get("ratio")))
        dynamic, task = _dynamic_key(problem)
        key = (
            problem.mechanism,
            tuple(problem.free),
            tuple(problem.fixed),
            tuple(problem.targets),
            cond,
            problem.objective,
            problem.size,
            problem.accel_over,
            tuple(sorted(branch.items())),
            orientation,
            range_target,
            sense,
            guarded,
            coarse,
            *dynamic,
        )
        if task is not None:
            self._tasks[task] = self._tasks.pop(task, set()) | {key}
            while len(self._tasks) > self.KEPT_TASKS:
                for old in self._tasks.pop(next(iter(self._tasks))):
                    self._built.pop(old, None)
        f = self._built.get(key)
        if f is None:
            f = self._built[key] = Formulation(
                problem, branch, orientation, range_target, sense, self.samples, self.extra, guarded, coarse
            )
        return f


class LocalSolve:
    """One start to one candidate, on a backend, with the exchange loop. tolerances: {'feasibility', 'gap'}. A
    start given with a nearby problem's optimum at its design (a chart's neighbour) is first continued by Newton on
    that optimum's active set (``newton``), the backend running only where that is not verified."""

    def __init__(self, formulations: Formulations, backend, tolerances: dict, max_rounds: int, settings=DEFAULT):
        self.formulations, self.backend = formulations, backend
        self.tolerances, self.max_rounds, self.settings = tolerances, max_rounds, settings

    def run(
        self,
        problem,
        values0,
        branch,
        targets,
        *,
        orientation=None,
        max_rounds=None,
        range_target=None,
        sense=1,
        designs=None,
        bound=None,
        patient=False,
        near=False,
        hint=None,
        deadline=None,
    ) -> Candidate:
        """From values0 on branch; orientation: which way the TR equality is met (+1, -1), None for the start's
        own; designs: the solve's memo of built mechanisms; bound: the incumbent's NLP objective value, above
        which the exchange loop stops (the start is pruned); patient: a start near an optimum of a nearby problem,
        run on the backend's ``patient()`` variant (a larger iteration limit) where it has one; near: a start at an
        optimum of a nearby problem, run on the backend's ``near()`` variant (a small, monotone barrier) where it has
        one; deadline: no exchange round starts after it (perf_counter s; the candidate is then not certified)."""
        max_rounds = self.max_rounds if max_rounds is None else max_rounds
        backend = self.backend.patient() if patient and hasattr(self.backend, "patient") else self.backend
        # a re-solve starts at the last round's optimum: from the small barrier too (fewer IPOPT runs and
        # iterations to the same design than from the default barrier)
        warm_backend = backend.near() if hasattr(backend, "near") else backend
        backend = warm_backend if near else backend
        designs = designs or Designs()
        objective = criteria.of_problem(problem)
        continued = self._continued(problem, values0, branch, targets, orientation, range_target, sense, hint)
        if (
            continued is None
            and objective is not None
            and not objective.kinematic
            and range_target is None
            and not _meets(problem, values0, branch, targets, designs)
        ):
            # a dynamic objective from a design that meets the targets: its forces change fast where the loop nears
            # a limit, and a start far from the targets leads IPOPT there (a feasibility solve first, so that the
            # objective's run starts on the targets)
            pre = self.run(
                self._feasibility(problem),
                values0,
                branch,
                targets,
                orientation=orientation,
                max_rounds=1,
                designs=designs,
            )
            if pre.converged and not pre.residuals_over(self.tolerances["feasibility"]):
                values0, orientation = pre.values, pre.orientation
        if continued is None:
            th0, orientation = starts_.dead_centre_start(
                problem, values0, branch, targets, orientation, range_target, designs
            )
            form = self.formulations.get(
                problem, branch, orientation, range_target, sense, coarse=self.settings.coarse_nodes
            )
            samples, fractions = form.base_samples()
            used = used_f = form.n_base
            phi, box, turn = form.lifted_start(form.concrete(problem), values0, designs, th0)
            p = form.param_vector(problem, targets, samples, fractions, box=box)
            w = form.epigraph_start(form.pack(values0, th0, phi=phi, box=box, turn=turn), p)
        else:  # the start's optimum continued here: its samples, its point (a box is set from the design later)
            form, p, _ = continued
            samples, fractions = hint.blocks["samples"].copy(), hint.blocks["fractions"].copy()
            (used, used_f), box = hint.used, None
        lbx, ubx = form.bounds(problem)
        moved, moved_f = np.full(samples.size, np.nan), np.full(fractions.size, np.nan)  # (``place``)
        c = Candidate(False, dict(values0), branch, orientation)
        gap_tol, feas_tol = self.tolerances["gap"], self.tolerances["feasibility"]
        g, info, m, restarts, polished, polish = None, {}, None, 0, False, None
        relifts = 0
        first = continued[2] if continued is not None else None
        rounds = []  # what each round's certificate asked (``_stuck``)
        while c.rounds < max_rounds:
            if c.rounds and deadline is not None and time.perf_counter() >= deadline:
                break
            c.rounds += 1
            warm = c.rounds > 1  # a re-solve: from the small barrier, unless a start not near an optimum ended at a
            # design that turned back in a stroke (its optimum is not near)
            small = warm and (near or not info.get("guard"))
            run, first = first, None
            if run is None:
                run = (warm_backend if small else backend).run(form, w, p, lbx, ubx, warm=warm)
            ran, last = form, run
            w, g = run.w, run.g
            c.t_ipopt += run.seconds
            c.iterations += run.iterations
            c.statuses.append(run.message)
            c.ends.append(run.status)
            pt = form.unpack(w)
            c.values = pt.values
            c.problem = form.concrete(problem, pt.z)
            m, info, add, frac = certify(
                problem, form, c.values, branch, pt.theta, pt.z, run.f, gap_tol, feas_tol, designs, c.problem
            )
            if polish is not None:  # the warm run after an acceptable end: kept if it converges and certifies
                if not run.converged or not info.get("ok"):
                    w, g, c.values, c.problem, m, info, c.ends[-1], c.statuses[-1] = polish
                    last = None
                    break
                polish = None
            close = range_target or max(form.violations(g).values(), default=0.0) <= self.settings.restart_violation
            if run.status in (Status.ITERATION_LIMIT, Status.STALLED) and restarts < self.settings.restarts and close:
                restarts += 1  # the iteration budget ran out, or the steps stalled, near a design: go on from there
                continue
            # a dynamic objective's run that ran out of iterations far from a design: the torque's extremes move,
            # merge and appear as the design changes, and a lifted angle whose extreme merged cannot meet its
            # stationarity row (even from a start that met every row). Go on from there with each lifted angle at an
            # extreme of the design it reached (``lifted_start``)
            if (
                run.status is Status.ITERATION_LIMIT
                and relifts < self.settings.relifts
                and form.n_lift
                and objective is not None
                and not objective.kinematic
                and not range_target
            ):
                pt = form.unpack(w)
                phi, _, _ = form.lifted_start(form.concrete(problem, pt.z), pt.values, designs, None)
                if phi is not None:
                    relifts += 1
                    w = form.epigraph_start(form.with_lifts(w, phi), p)
                    continue
            if not run.converged and not range_target:
                break
            caps = form.caps(w, p)
            tightened = not np.array_equal(caps, form.p_blocks.split(p)["caps"])
            turned = info.get("monotone", [])  # where the output turned back inside a stroke: a lifted angle there
            guarding = bool(info.get("guard")) and not form.guarded
            if guarding:  # the same NLP with the rows that state where the output reverses (the certifier's angles
                # sampled), from where it is
                form = self.formulations.get(problem, branch, orientation, range_target, sense, guarded=True)
                lbx, ubx = form.bounds(problem)
            refining = form.coarse  # the coarse rule's optimum: on to the certifier's rule from there
            if refining:
                form = self.formulations.get(problem, branch, orientation, range_target, sense, guarded=form.guarded)
            if (turned or guarding) and m is not None:
                w = form.with_turns(w, m, turned)
            if not add and not frac and not tightened and not turned and not guarding and not refining:
                if run.status is Status.ACCEPTABLE and not polished and c.rounds < max_rounds:
                    # IPOPT's looser tolerance: once more from there, warm, to its own (the acceptable point kept)
                    polished, polish = True, (w, g, c.values, c.problem, m, info, run.status, run.message)
                    continue
                break
            if bound is not None and info.get("ok") and run.f > bound + 1e-9 * max(1.0, abs(bound)):
                c.pruned = True  # more samples only raise this basin's NLP value: it cannot beat the incumbent
                break
            rounds.append((info.get("ok"), info.get("reason"), run.f, np.sort(add), np.sort(frac)))
            if _stuck(rounds, self.settings.exchange_stuck):
                break  # the same design and angles to add, ``exchange_stuck`` rounds running: the next ones are too
            used = place(samples, used, add, TWO_PI, 0.05, form.n_base, moved)
            used_f = place(fractions, used_f, frac, 1.0, 0.01, form.n_base, moved_f)
            if form.n_box and m is not None:  # each box side lifted at the coordinate that reaches it now
                box = m.bounding_box()
                w = form.with_box(w, box)
            if form.n_lift and m is not None:  # every largest extreme of this design lifted
                w = form.relifted(w, c.problem or problem, c.values, designs)
            p = form.param_vector(problem, targets, samples, fractions, box=box, caps=caps)
            w = form.epigraph_start(w, p) if info.get("gap", 0) > 0 or not info.get("ok") else w
        c.mechanism, c.info = m, info
        c.residuals = residuals(c.problem or problem, ran.violations(g), m, {k: targets[k] for k in form.targets})
        c.ok = bool(info.get("ok")) and c.converged and self.within(c) and not c.pruned
        if c.ok and last is not None and last.lam_g is not None and ran is form and range_target is None:
            c.hint = newton.Hint.of(form, c.values, last, p, (used, used_f))
        return c

    def _continued(self, problem, values0, branch, targets, orientation, range_target, sense, hint):
        """(formulation, p, run) where ``hint`` is the optimum at values0 of this problem's formulation and Newton
        continues it here (``newton.correct``, verified); None otherwise (the start is built and run as any)."""
        if hint is None or orientation is None or range_target is not None:
            return None
        form = self.formulations.get(problem, branch, orientation, range_target, sense)
        if not hint.fits(form, values0):
            return None
        base = form.p_blocks.split(form.param_vector(problem, targets, *form.base_samples()))
        p = form.p_blocks.join(**{**base, **hint.blocks})
        lbx, ubx = form.bounds(problem)
        run = newton.correct(form, hint, p, lbx, ubx, self.settings)
        return None if run is None else (form, p, run)

    def _feasibility(self, problem):
        """The problem without its objective (its targets, conditions and bounds), built once per problem."""
        memo = self.__dict__.setdefault("_feasibility_of", {})
        if problem not in memo:
            if len(memo) >= MEMO:
                memo.clear()
            memo[problem] = problem.replace(objective=None)
        return memo[problem]

    def polish(self, problem, values0, branch, targets, designs=None) -> Candidate:
        """Newton on the target and dead-centre equations from a closed-form point of a square problem (as many
        free parameters as targets): the point of the finite solution set that the closed form names."""
        designs = designs or Designs()
        th0, orientation = starts_.dead_centre_start(problem, values0, branch, targets, None, None, designs)
        form = self.formulations.get(problem, branch, orientation)
        rows = form.square_rows
        if rows is None or form.concrete(problem) is not problem:  # a free counterweight: the NLP chooses it
            return self.run(problem, values0, branch, targets, orientation=orientation, designs=designs)
        p = form.param_vector(problem, targets, *form.base_samples())
        w = form.pack(values0, th0)
        d = form.design  # the design block of w: free parameters and dead centres
        c = Candidate(False, dict(values0), branch, orientation, origin="enumeration")
        for _ in range(30):
            out = form.square_system(np.concatenate([w, p])[None, :])[0]
            try:
                n = d.stop - d.start
                step = np.linalg.solve(out[n:].reshape(n, n, order="F"), out[:n])
            except np.linalg.LinAlgError:
                break
            w[d] -= step
            c.iterations += 1
            if np.max(np.abs(step)) <= 1e-14 * max(1.0, np.max(np.abs(w[d]))):
                break
        pt = form.unpack(w)
        c.statuses, c.ends = ["enumerated point (Newton)"], [Status.SOLVED]
        inside = all(lo - 1e-12 <= pt.values[k] <= hi + 1e-12 for k, (lo, hi) in problem.free.items())
        if not np.all(np.isfinite(w[d])) or not inside:
            c.info = {
                "ok": False,
                "reason": "Newton on the target equations leaves the bounds from the closed form's "
                "point (it meets the targets only approximately: no design there)",
            }
            c.ends = [Status.FAILED]
            return c
        # the closed form's own values where Newton only moved them by rounding (one design built, not two)
        c.values = {
            k: values0[k] if abs(v - values0[k]) <= 4e-16 * abs(values0[k]) else v for k, v in pt.values.items()
        }
        return self._certified(problem, form, c, pt.theta, p, targets, designs)

    def evaluate(self, problem, values, branch, targets, designs=None) -> Candidate:
        """The certificate of a design as it is, without a backend run (a point a closed form puts on the targets,
        ``MultiStart.walked``): exact evaluation of its targets, rules, conditions and objective."""
        designs = designs or Designs()
        th0, orientation = starts_.dead_centre_start(problem, values, branch, targets, None, None, designs)
        form = self.formulations.get(problem, branch, orientation)
        c = Candidate(False, dict(values), branch, orientation, origin="walk")
        c.statuses, c.ends = ["evaluated as given"], [Status.SOLVED]
        if form.concrete(problem) is not problem:  # a free counterweight: only the NLP chooses it
            c.info, c.ends = {"ok": False, "reason": "a free counterweight is chosen by the NLP"}, [Status.FAILED]
            return c
        p = form.param_vector(problem, targets, *form.base_samples())
        return self._certified(problem, form, c, th0, p, targets, designs)

    def _certified(self, problem, form, c, theta, p, targets, designs) -> Candidate:
        """Candidate c (its values, at dead centres theta) certified by exact evaluation."""
        w = form.epigraph_start(form.pack(c.values, theta), p)
        g = form.constraint_values(np.concatenate([w, p])[None, :])[0]
        tol = self.tolerances
        m, info, _, _ = certify(
            problem, form, c.values, c.branch, theta, None, None, tol["gap"], tol["feasibility"], designs
        )
        c.mechanism, c.info = m, info
        c.residuals = residuals(problem, form.violations(g), m, {k: targets[k] for k in form.targets})
        c.ok = bool(info.get("ok")) and self.within(c)
        return c

    def within(self, c: Candidate) -> bool:
        tol = self.tolerances
        return max(c.residuals.values(), default=0.0) <= tol["feasibility"] and c.info.get("gap", 0.0) <= tol["gap"]


def _meets(problem, values, branch, targets, build, tol: float = 1e-9) -> bool:
    """Whether the design at ``values`` builds and meets the targets (to tol relative)."""
    try:
        got = target_values(build(problem, values, branch))
    except QroptError:
        return False
    return all(abs(got[k] - v) <= tol * max(1.0, abs(v)) for k, v in targets.items() if k in got)


def _stuck(rounds, stuck: int) -> bool:
    """Whether the exchange loop's last ``stuck`` rounds ended alike: the same verdict and reason, NLP values within
    1e-9 (relative) and the same angles and fractions to add (to 1e-9): the loop goes round without moving (at a
    design whose dead centres are local, say)."""
    if len(rounds) < stuck:
        return False
    ok, why, f, add, frac = rounds[-1]
    for ok2, why2, f2, add2, frac2 in rounds[-stuck:-1]:
        if (ok2, why2) != (ok, why) or abs(f2 - f) > 1e-9 * max(1.0, abs(f)):
            return False
        if add2.shape != add.shape or frac2.shape != frac.shape:
            return False
        if not (np.allclose(add2, add, rtol=0, atol=1e-9) and np.allclose(frac2, frac, rtol=0, atol=1e-9)):
            return False
    return True


def place(slots, used, new, period, near, base, before=None):
    """Put new sample angles into the extra slots: an angle close to an extra sample moves it there (the
    worst angle drifts as the design changes), others take free slots; with every slot taken, the nearest
    extra sample moves (an angle the exact evaluation names is never dropped). ``before``: each slot's angle
    before its last move (NaN where it has not moved), kept here: an angle nearer a sample's former place than
    to the sample takes a free slot instead (the worst angle swings between two places, and the NLP needs
    both). Returns the slots in use."""

    def apart(a, t):
        return np.abs((a - t + period / 2) % period - period / 2)

    for t in new:
        extra = np.arange(base, used)
        if extra.size:
            d = apart(slots[extra], t)
            k = int(np.argmin(d))
            back = before is not None and apart(before[extra[k]], t) < d[k]  # False where it has not moved (NaN)
            if (d[k] < near and not back) or used == slots.size:
                if before is not None:
                    before[extra[k]] = slots[extra[k]]
                slots[extra[k]] = t
                continue
        if used < slots.size:
            slots[used] = t
            used += 1
    return used


def nlp_value(problem, info) -> float:
    """A certified objective in the NLP's terms (what the backend minimises)."""
    return criteria.of_problem(problem).to_nlp(info["certified"], problem.omega2)


__all__ = ["Candidate", "Formulations", "LocalSolve", "place", "nlp_value"]
