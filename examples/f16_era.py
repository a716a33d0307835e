"""ERA on the F-16 ground vibration test: find the wing bending mode near 5.2 Hz.

The record (nonlinearbenchmark.org) has a shaker force as input and three accelerations as
outputs, sampled at 400 Hz, excited by a 2-15 Hz multisine of 9 periods of 8192 samples. The
first period holds the transient and is dropped. Because nothing above 15 Hz is excited, the
record is decimated by 8 (fs = 50 Hz) before OKID estimates the Markov parameters; ERA then
realises a model whose modes are judged by their damping and modal amplitude coherence.

Run: ``python examples/f16_era.py [path/to/F16Data_FullMSine_Level1.csv]`` (default: the
copy bundled with sysid, ``sysid.datasets.path("f16")``).
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
from scipy import signal

import sysid

DEFAULT = Path(sysid.datasets.path("f16"))
PERIOD = 8192
FS = 400.0
DECIMATE = 8


def load(path: Path = DEFAULT) -> sysid.IOData:
    """Force -> three accelerations, first period dropped, decimated to 50 Hz."""
    # columns: Force, Voltage, Acceleration1-3, Fs (trailing comma: an empty last field)
    raw = np.genfromtxt(path, delimiter=",", skip_header=1, usecols=(0, 2, 3, 4))
    u, y = raw[PERIOD:, :1], raw[PERIOD:, 1:]
    u = signal.decimate(u - u.mean(0), DECIMATE, ftype="fir", zero_phase=True, axis=0)
    y = signal.decimate(y - y.mean(0), DECIMATE, ftype="fir", zero_phase=True, axis=0)
    return sysid.IOData(u, y, dt=DECIMATE / FS, input_names=["force"],
                        output_names=["acc1", "acc2", "acc3"])


def markov(data: sysid.IOData) -> sysid.MarkovEstimate:
    """OKID with observer order 20: 301 Markov parameters (6 s at 50 Hz); the accelerations
    answer the force within the sample, so ``h_0 = D`` is estimated."""
    return sysid.okid(data, observer_order=20, count=301, feedthrough=True)


def identify(data: sysid.IOData) -> sysid.EraResult:
    """ERA of order 30 on a 100 x 200 block Hankel matrix of the OKID Markov parameters."""
    return markov(data).era(order=30, rows=100, cols=200)


def stabilization(data: sysid.IOData) -> sysid.StabilizationDiagram:
    """ERA at orders 10, 12, ..., 40: physical modes stay put as the order grows."""
    return sysid.era_stabilization(markov(data), range(10, 42, 2), rows=100, cols=200)


def physical_modes(result: sysid.EraResult) -> sysid.ModalAnalysis:
    """Modes in the excited band, lightly damped and coherent (MAC > 0.9)."""
    modes = result.modes()
    keep = ((modes.frequencies_hz > 2) & (modes.frequencies_hz < 15) & (modes.damping < 0.05)
            & (modes.extra["mac"] > 0.9))
    return modes.select(keep)


def main(argv: list[str]) -> sysid.ModalAnalysis:
    path = Path(argv[1]) if len(argv) > 1 else DEFAULT
    data = load(path)
    result = identify(data)
    modes = physical_modes(result)
    print(data)
    print(f"ERA: order {result.order}, Hankel {result.rows}x{result.cols} blocks")
    print(modes)
    print(stabilization(data))
    return modes


if __name__ == "__main__":
    main(sys.argv)
