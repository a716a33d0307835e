"""Results do not depend on the number of threads: compression, singular values and fitted
models are bit-for-bit the same with 1, 2 and 3 rayon threads (each run in a fresh process,
since the pool size is read from ``RAYON_NUM_THREADS`` once per process)."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest

SCRIPT = r"""
import hashlib, json, sys
import numpy as np
import sysid
from sysid import _sysid

rng = np.random.default_rng(3)
A = np.diag([0.9, 0.7, -0.5, 0.3, 0.6, -0.2])
true = sysid.StateSpaceModel(A, rng.standard_normal((6, 3)), rng.standard_normal((3, 6)))
n = 40_000
u = rng.standard_normal((n, 3))
y = true.simulate(u) + 0.1 * rng.standard_normal((n, 3))

def h(a):
    return hashlib.sha256(np.ascontiguousarray(a, dtype=np.float64).tobytes()).hexdigest()

out = {}
for comp in sys.argv[1:]:
    # chunk_rows small enough that the QR path has many blocks to share out
    f = _sysid.compress([(u, y)], 10, 10, 256 if comp == "qr" else None, comp)
    est = sysid.SubspaceEstimator.from_factor(f)
    model = est.fit(6)
    out[comp] = {
        "source": f.source,
        "L": h(f.l),
        "sv": h(est.singular_values),
        "markov": h(model.markov(20)),
        "A": h(model.A),
        "B": h(model.B),
        "C": h(model.C),
        "D": h(model.D),
    }
print(json.dumps(out))
"""


def _run(threads: int, compressors: list[str]) -> dict:
    env = dict(os.environ, RAYON_NUM_THREADS=str(threads))
    res = subprocess.run(
        [sys.executable, "-c", SCRIPT, *compressors],
        env=env, capture_output=True, text=True, timeout=600, check=False,
    )
    assert res.returncode == 0, res.stderr
    return json.loads(res.stdout.strip().splitlines()[-1])


@pytest.mark.parametrize("compressors", [["qr", "correlation", "auto"]])
def test_bit_identical_for_1_2_3_threads(compressors: list[str]) -> None:
    runs = {t: _run(t, compressors) for t in (1, 2, 3)}
    for comp in compressors:
        ref = runs[1][comp]
        for t in (2, 3):
            assert runs[t][comp] == ref, (comp, t, runs[t][comp], ref)
