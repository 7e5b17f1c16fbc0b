"""The global strategies' candidates joined to the pool. Where the first pass certified none but they found
designs, the searches the diagnosis would run first (the second pass, the wider multi-start: ``searched``) run
here, and the best of all is taken."""

from __future__ import annotations

from qropt.synthesis.search.base import Stage
from qropt.synthesis.search.diagnosis import searched


class SecondPass(Stage):
    name = "joined"
    finishing = True

    def run(self, problem, pool, context):
        found = any(c.ok for c in pool.more) or pool.ends
        if pool.retry is not None and found and not pool.good and not context.out_of_time():
            pool.candidates, pool.claim, pool.plan = searched(
                context, problem, pool.plan, pool.candidates, pool.claim, pool.retry
            )
        pool.candidates += pool.more
        pool.more = []
