"""Shared test helpers: random stable systems and an independent numpy simulator."""

from __future__ import annotations

import os
import signal

import numpy as np
from hypothesis import settings

# CI runs the same examples every time (reproducible); locally hypothesis explores anew.
settings.register_profile("ci", derandomize=True, print_blob=True)
if os.environ.get("CI"):
    settings.load_profile("ci")

# A test run started in the background by a non-interactive shell inherits SIGINT ignored,
# and so would every process the Ctrl-C tests start (an ignored signal stays ignored across
# exec, and Python then installs no KeyboardInterrupt handler): catch it here, so that the
# children start with the default and the tests send a signal that is heard.
if signal.getsignal(signal.SIGINT) is signal.SIG_IGN:
    signal.signal(signal.SIGINT, signal.default_int_handler)

def random_system(n, m, l, rng, rmin=0.3, rmax=0.9, feedthrough=True):
    """A random stable (A, B, C, D) with well-separated pole moduli in [rmin, rmax]."""
    blocks = []
    i = 0
    radii = np.linspace(rmin, rmax, n) + 0.02 * rng.standard_normal(n)
    rng.shuffle(radii)
    while i < n:
        r = radii[i]
        if i + 1 < n and rng.random() < 0.6:
            th = 0.3 + 2.4 * rng.random()
            blocks.append(r * np.array([[np.cos(th), np.sin(th)], [-np.sin(th), np.cos(th)]]))
            i += 2
        else:
            blocks.append(np.array([[r if rng.random() < 0.5 else -r]]))
            i += 1
    a = np.zeros((n, n))
    k = 0
    for b in blocks:
        s = b.shape[0]
        a[k : k + s, k : k + s] = b
        k += s
    t = np.eye(n) + 0.3 * rng.standard_normal((n, n))
    a = t @ a @ np.linalg.inv(t)
    b = rng.standard_normal((n, m))
    c = rng.standard_normal((l, n))
    d = rng.standard_normal((l, m)) if feedthrough else np.zeros((l, m))
    return a, b, c, d


def simulate(a, b, c, d, u, x0=None, w=None, v=None):
    """x(t+1) = A x + B u + w, y = C x + D u + v (plain numpy, independent of sysid)."""
    n = a.shape[0]
    N = u.shape[0]
    x = np.zeros(n) if x0 is None else np.array(x0, dtype=float)
    xs = np.empty((N, n))
    bu = u @ b.T
    if w is not None:
        bu = bu + w
    for t in range(N):
        xs[t] = x
        x = a @ x + bu[t]
    y = xs @ c.T + u @ d.T
    if v is not None:
        y = y + v
    return y


def markov(a, b, c, d, count):
    out = [d]
    ab = b
    for _ in range(1, count):
        out.append(c @ ab)
        ab = a @ ab
    return np.array(out)


def match_poles(p_est, p_true):
    """Max distance between two pole sets after optimal pairing."""
    from scipy.optimize import linear_sum_assignment

    cost = np.abs(np.subtract.outer(np.asarray(p_est), np.asarray(p_true)))
    r, c = linear_sum_assignment(cost)
    return float(cost[r, c].max())
