"""Alternation and cadence of an evaluated policy with brief lift-offs merged into the stance.

A foot that leaves the ground for fewer than N control steps inside a stance counts as a new
touchdown of the same foot, which lowers the alternation of `esrl eval` (the metric's
definition, `esrl_metrics::cycle`, is unchanged). This recomputes it from the contact traces
with such gaps filled, to show how much of a low alternation is foot chatter.

Usage: python debounce.py RUN/eval.json [N ...]   (an eval.json with traces, as `esrl eval` writes;
N: lift-offs shorter than N control steps are merged; default 1 2 3, 1 = as measured).
The contact flags are the trace's (`Trace::contact`); in a few episodes the alternation
`esrl eval` prints differs from the "as measured" line by up to 0.03.
"""

import json
import sys

import numpy as np

import esrl_rs


def fill_gaps(contact: np.ndarray, n: int) -> np.ndarray:
    """`contact` with every run of False shorter than `n` between two True runs set True."""
    c = contact.copy()
    i, size = 0, len(c)
    while i < size:
        if c[i]:
            i += 1
            continue
        j = i
        while j < size and not c[j]:
            j += 1
        if i > 0 and j < size and j - i < n:
            c[i:j] = True
        i = j
    return c


def main():
    report = json.loads(open(sys.argv[1]).read())
    dt = 0.025
    for n in [int(a) for a in sys.argv[2:]] or [1, 2, 3]:
        alternation, cadence = [], []
        for ep in report["episodes"]:
            contact = np.asarray(ep["trace"]["contact"], dtype=bool)
            left, right = (fill_gaps(contact[:, k], n).tolist() for k in (0, 1))
            p = esrl_rs.metrics.gait_phases(left, right, dt)
            if p["alternation"] is not None:
                alternation.append(p["alternation"])
            if p.get("cadence"):
                cadence.append(p["cadence"])
        label = (
            "as measured"
            if n <= 1
            else f"lift-offs of at most {n - 1} control step(s) ({(n - 1) * dt * 1000:.0f} ms) merged"
        )
        print(f"{label}: alternation {np.mean(alternation):.2f}, cadence {np.mean(cadence):.0f}/min")


if __name__ == "__main__":
    main()
