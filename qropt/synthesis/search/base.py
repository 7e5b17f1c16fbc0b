"""The search's parts: the Strategy protocol, the Pool a solve's strategies share, the Context of one solve, and
the runner that walks a pipeline once.

A strategy says whether it applies to a problem and its plan of starts (``accepts``: what the problem and its
criterion declare, never a criterion's name) and then acts on the pool (``run``): it adds starts, runs local
solves, adds candidates and descent ends, or makes the Result. A strategy returns ``STOP`` to end the pipeline (or
the phase) it runs in. Each candidate keeps its provenance as data (``Candidate.origin``, ``parent`` and its cost);
the claim of the certificate is rendered from the pool's words when the Result is made.
"""

from __future__ import annotations

import dataclasses
import time
from dataclasses import dataclass, field
from typing import Any, ClassVar, Protocol, runtime_checkable

from qropt.errors import ProblemError
from qropt.synthesis.certificate import Designs

STOP = "stop"  # a strategy's run returns this to end the pipeline (or the phase) it runs in


@runtime_checkable
class Strategy(Protocol):
    """One stage of a solve. ``name``: a few words for claims and tables; a class attribute ``finishing = True``
    (optional) says it runs after a time limit too (it makes the Result of what was found, cheaply)."""

    name: ClassVar[str]

    def accepts(self, problem, plan) -> bool:
        """Whether it applies to ``problem`` with this plan of starts (``starts.Plan``; None before one is made)."""

    def run(self, problem, pool: Pool, context: Context) -> str | None:
        """Act on the pool; ``STOP`` ends the pipeline (or phase) it runs in."""


class Stage:
    """A convenient base for strategies: accepts every problem."""

    name: ClassVar[str] = ""
    finishing: ClassVar[bool] = False

    def accepts(self, problem, plan) -> bool:
        return True

    def __repr__(self):
        return f"<strategy {self.name}>"


@dataclass
class Pool:
    """What a solve's strategies share: the plan of starts, the queue of starts and the candidates they gave, the
    descent ends, the claim's words, the time each strategy spent, and the Result once one is made."""

    plan: Any = None  # starts.Plan
    designs: Designs = field(default_factory=Designs)  # every mechanism this solve builds, built once
    runs: list = field(default_factory=list)  # queued starts: (origin, values[, branch, ...])
    candidates: list = field(default_factory=list)  # local.Candidate, every one kept
    more: list = field(default_factory=list)  # candidates of the global strategies, merged after the second pass
    ends: list = field(default_factory=list)  # evolution.End, best first
    claim: str = ""  # what the best design rests on (a closed form's words, the atlas's)
    notes: list = field(default_factory=list)  # the global strategies' words: "with ..." in the claim
    retry: Any = None  # the multi-start's second pass, deferred (a callable) where the diagnosis may run it
    spent: dict = field(default_factory=dict)  # statistics the strategies add to the Result's
    ran: list = field(default_factory=list)  # (strategy name, seconds) in the order they ran
    skipped: list = field(default_factory=list)  # strategies that applied but did not run: the time limit had passed
    result: Any = None  # the Result, once made

    @property
    def good(self) -> list:
        """The certified candidates."""
        return [c for c in self.candidates if c.ok]

    @property
    def guard(self) -> str:
        """The global strategies' words, joined as the claim shows them."""
        return "; ".join(self.notes)


@dataclass
class Context:
    """One solve's options and the Solver's parts. given: starts given (free-parameter dicts), tried first;
    asked: whether ``starts_n`` was named (else grown with the free parameters); hint: a nearby optimum to
    continue (``newton.Hint``); t0: when the solve began (perf_counter s); deadline: when its time limit ends
    (perf_counter s), or None."""

    solver: Any
    targets: dict
    starts_n: int
    seed: int
    max_rounds: int
    given: list = field(default_factory=list)
    use_analytic: bool = True
    diagnose: bool = True
    asked: bool = False
    hint: Any = None
    t0: float = field(default_factory=time.perf_counter)
    deadline: float | None = None

    @property
    def settings(self):
        return self.solver.settings

    def out_of_time(self) -> bool:
        """Whether the solve's time limit has passed."""
        return self.deadline is not None and time.perf_counter() >= self.deadline

    def options(self, **changed) -> dict:
        """This solve's options as ``run`` takes them, some changed."""
        out = {
            "targets": self.targets,
            "starts_n": self.starts_n,
            "seed": self.seed,
            "max_rounds": self.max_rounds,
            "given": self.given,
            "use_analytic": self.use_analytic,
            "diagnose": self.diagnose,
            "asked": self.asked,
            "hint": self.hint,
            "deadline": self.deadline,
        }
        out.update(changed)
        return out

    def sub(self, problem, **changed):
        """The Result of another problem (a scaled copy, a bound's own optimum, a tie-break) by the Solver's
        pipeline: this solve's starts_n (as named, not grown again), seed, rounds and diagnosis, its own targets,
        the closed forms, no given starts, with these options changed (given starts and no diagnosis keep it
        short)."""
        base = {"targets": dict(problem.targets), "given": [], "use_analytic": True, "asked": True, "hint": None}
        opts = self.options(**{**base, **changed})
        return solve(self.solver.pipeline, problem, Context(self.solver, **opts))

    def multistart(self, problem, plan, starts_n, seed, designs=None, *, retry=True, max_rounds=None):
        """The Solver's starts phase on ``problem`` with ``plan`` and no given starts: (candidates, claim, the
        deferred second pass or None). retry: run the second pass here where it applies."""
        pool = Pool(plan=plan, designs=designs if designs is not None else Designs())
        rounds = self.max_rounds if max_rounds is None else max_rounds
        changed = {"starts_n": starts_n, "seed": seed, "given": [], "diagnose": not retry, "hint": None}
        ctx = Context(self.solver, **self.options(max_rounds=rounds, **changed))
        run(self.solver.starts, problem, pool, ctx)
        return pool.candidates, pool.claim, pool.retry


def run(stages, problem, pool: Pool, context: Context) -> str | None:
    """Each strategy of ``stages`` that accepts the problem, in order, until one returns STOP (returned)."""
    for s in stages:
        if not s.accepts(problem, pool.plan):
            continue
        if context.out_of_time() and not getattr(s, "finishing", False):
            pool.skipped.append(s.name)
            continue
        t = time.perf_counter()
        said = s.run(problem, pool, context)
        pool.ran.append((s.name, time.perf_counter() - t))
        if said == STOP:
            return STOP
    return None


def solve(stages, problem, context: Context):
    """The Result of one pass of ``stages`` over a fresh pool (a pipeline must make one); its stats name the
    strategies that ran (``strategies``) and the seconds each took (``t_strategies``; a phase's include its own
    strategies'), those of the pass that made it where another pass made it."""
    pool = Pool()
    run(stages, problem, pool, context)
    if pool.result is None:
        names = [s.name for s in stages]
        raise ProblemError(f"the pipeline {names} made no Result (it needs a strategy that makes one, as Failed does)")
    r = pool.result
    if pool.skipped:
        r = timed_out(r, list(dict.fromkeys(pool.skipped)), context)
    if "strategies" in r.stats:
        return r
    spent: dict = {}
    for name, seconds in pool.ran:
        spent[name] = spent.get(name, 0.0) + seconds
    return dataclasses.replace(r, stats={**r.stats, "strategies": list(spent), "t_strategies": spent})


def timed_out(r, skipped: list, context: Context):
    """The Result with its claim (and message) saying that the time limit left these strategies out."""
    limit = context.deadline - context.t0
    words = f"the time limit ({limit:g} s) left out: {', '.join(skipped)}"
    stats = {**r.stats, "skipped": [*r.stats.get("skipped", []), *skipped]}
    if r.certificate is None:
        return dataclasses.replace(r, message=f"{r.message}; {words}", stats=stats)
    claim = f"{r.certificate.global_claim}; {words}"
    cert = dataclasses.replace(r.certificate, global_claim=claim)
    message = r.message.replace(r.certificate.global_claim, claim)
    return dataclasses.replace(r, certificate=cert, message=message, stats=stats)


@dataclass(frozen=True)
class Phase(Stage):
    """A named list of strategies run as one (a STOP inside ends the phase only)."""

    name: ClassVar[str] = "starts phase"
    stages: tuple = ()

    def run(self, problem, pool, context):
        run(self.stages, problem, pool, context)


__all__ = ["Strategy", "Stage", "Pool", "Context", "Phase", "run", "solve", "STOP"]
