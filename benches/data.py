"""Seeded benchmark data: random stable MIMO systems with process and measurement noise.

x(t+1) = A x + B u + w,  y = C x + v,  u, w, v white Gaussian (w, v with standard deviation
0.1 and 0.1). The record is simulated in chunks by sysid's Rust simulator (the state is
carried over by simulating [C; I] as outputs) and written to a .npy file (samples, m + l),
so that records larger than memory can be made.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np


def random_system(nx: int, m: int, l: int, seed: int) -> tuple[np.ndarray, ...]:
    """A, B, C with poles of radius 0.5 to 0.95 (complex pairs and reals)."""
    rng = np.random.default_rng(seed)
    blocks = []
    k = 0
    while k < nx:
        r = rng.uniform(0.5, 0.95)
        if nx - k >= 2 and rng.random() < 0.7:
            th = rng.uniform(0.1, 2.5)
            blocks.append(r * np.array([[np.cos(th), -np.sin(th)], [np.sin(th), np.cos(th)]]))
            k += 2
        else:
            blocks.append(np.array([[r * rng.choice([-1.0, 1.0])]]))
            k += 1
    a0 = np.zeros((nx, nx))
    i = 0
    for b in blocks:
        s = b.shape[0]
        a0[i : i + s, i : i + s] = b
        i += s
    q, _ = np.linalg.qr(rng.standard_normal((nx, nx)))
    t = q @ np.diag(rng.uniform(0.5, 2.0, nx)) @ q.T
    a = t @ a0 @ np.linalg.inv(t)
    b = rng.standard_normal((nx, m))
    c = rng.standard_normal((l, nx))
    return a, b, c


def generate(
    path: Path, n: int, m: int, l: int, nx: int, seed: int, chunk: int = 1_000_000,
    noise_seed: int | None = None,
) -> np.ndarray:
    """Writes the record to `path` (.npy); returns the true poles. The system depends on
    `seed` only; inputs and noise on `noise_seed` (default `seed + 1`), so a validation
    record of the same system is `generate(..., seed, noise_seed=other)`."""
    from sysid import _sysid

    a, b, c = random_system(nx, m, l, seed)
    rng = np.random.default_rng(seed + 1 if noise_seed is None else noise_seed)
    b_aug = np.hstack([b, np.eye(nx)])
    c_aug = np.vstack([c, np.eye(nx)])
    d_aug = np.zeros((l + nx, m + nx))
    out = np.lib.format.open_memmap(path, mode="w+", dtype=np.float64, shape=(n, m + l))
    x0 = np.zeros(nx)
    for s in range(0, n, chunk):
        e = min(n, s + chunk)
        u = rng.standard_normal((e - s, m))
        w = 0.1 * rng.standard_normal((e - s, nx))
        ux = np.ascontiguousarray(np.hstack([u, w]))
        yx = _sysid.simulate(a, b_aug, c_aug, d_aug, ux, x0)
        y = yx[:, :l] + 0.1 * rng.standard_normal((e - s, l))
        x0 = a @ yx[-1, l:] + b_aug @ ux[-1]
        out[s:e, :m] = u
        out[s:e, m:] = y
    out.flush()
    del out
    return np.linalg.eigvals(a)


def estimation_validation_file(path: Path, make: Any, n: int, n_val: int) -> Path:
    """``path``, an .npz of an estimation record (``u``, ``y``: ``make(n, seed=1)``) and a
    validation record (``uv``, ``yv``: ``make(n_val, seed=2)``), written on first use."""
    path.parent.mkdir(exist_ok=True)
    if not path.exists():
        u, y = make(n, 1)
        uv, yv = make(n_val, 2)
        np.savez(path, u=u, y=y, uv=uv, yv=yv)
    return path
