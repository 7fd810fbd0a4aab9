"""Multi-hop routes through the radios of the wireless simulation (docs/wireless.md, "Relays"):
once robots have dropped relays, a message whose direct link does not hold goes the way whose
links are most likely to carry it, through relays and other robots.

The best route maximises the product of its hops' qualities (the share of messages each lets
through), that is the shortest path with each hop costing -log(quality), found by Dijkstra's
algorithm (E. W. Dijkstra, "A note on two problems in connexion with graphs", Numerische
Mathematik 1, 1959), ties broken by name so that every run finds the same route."""

from __future__ import annotations

import heapq
import math
from collections.abc import Callable, Sequence

# A hop whose quality is below this carries too little to route through (one message in a
# thousand)
MIN_HOP_QUALITY = 1e-3


def best_route(
    src: str, dst: str, nodes: Sequence[str], quality: Callable[[str, str], float | None]
) -> list[str] | None:
    """The names from ``src`` to ``dst`` (both included) of the route whose hops' qualities have
    the largest product, over the hops for which ``quality(a, b)`` is at least MIN_HOP_QUALITY
    (None: the link does not hold); None when there is no route.  ``nodes``: every radio."""
    if src == dst:
        return [src]
    best = {src: 0.0}
    before: dict[str, str] = {}
    heap: list[tuple[float, str]] = [(0.0, src)]
    done: set[str] = set()
    while heap:
        cost, node = heapq.heappop(heap)
        if node in done:
            continue
        if node == dst:
            path = [dst]
            while path[-1] != src:
                path.append(before[path[-1]])
            return path[::-1]
        done.add(node)
        for other in nodes:
            if other in done or other == node:
                continue
            q = quality(node, other)
            if q is None or q < MIN_HOP_QUALITY:
                continue
            c = cost - math.log(min(q, 1.0))
            if c < best.get(other, math.inf) - 1e-12:
                best[other] = c
                before[other] = node
                heapq.heappush(heap, (c, other))
    return None
