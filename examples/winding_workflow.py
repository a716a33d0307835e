"""Look at a record before fitting anything: the data workflow of a flight-test report, on
the DaISy industrial winding process (5 inputs, 2 outputs, dt = 0.1 s).

load -> check the sample time -> select -> detrend -> split -> coherence, spectra,
correlation, ETFE and spectral analysis -> a subspace model compared with the spectral estimate.

Run:  python examples/winding_workflow.py [path/to/winding.dat] [--plot OUTDIR]
(default: the copy bundled with sysid, ``sysid.datasets.path("winding")``).
"""

from __future__ import annotations

import sys
import warnings
from pathlib import Path
from typing import Any

import numpy as np

import sysid

DEFAULT = Path(sysid.datasets.path("winding"))


def main(path: str | Path = DEFAULT, plot_dir: str | Path | None = None) -> dict[str, Any]:
    raw = np.loadtxt(path)
    time = 0.1 * np.arange(raw.shape[0])  # a logger's time stamps
    dt = sysid.sample_time(time)  # median spacing, after a uniformity check
    data = sysid.IOData(
        u=raw[:, :5], y=raw[:, 5:7], time=time,
        input_names=["S1", "S2", "S3", "I1", "I3"],  # reel speeds, motor current set-points
        output_names=["T1", "T3"],                    # web tensions
    )
    print(data)
    print(data.summary())

    # select: cut out stretches where no input moves, then detrend what is left
    sel = sysid.drop_quiet(data, window=50, threshold=0.05)
    pre = sysid.detrend(sel, "linear")
    est, val = pre.split(0.6)
    print("estimation:", est)
    print("validation:", val)

    # which input drives which output, and where in frequency
    coh = sysid.coherence(est, nperseg=128)
    print(coh)
    strong = {
        (o, i): float(coh.band(0.6)[:, a, b].mean())
        for a, o in enumerate(coh.output_names) for b, i in enumerate(coh.input_names)
    }
    spectra = sysid.spectra(est, nperseg=128)
    corr = sysid.correlation(est, max_lag=30)
    lags = {o: [k for k in corr.significant(o, "S1").tolist() if k >= 0][:5]
            for o in est.output_names}
    print("first lags >= 0 where a tension correlates with S1:", lags)
    print("mean multiple coherence (all inputs together):",
          np.round(coh.multiple.mean(axis=0), 2))

    # frequency responses: raw and smoothed ETFE on equal-length data, Blackman-Tukey
    spa = sysid.spa(est, lags=40)
    smoothed = sysid.etfe(est, smoothing=31)
    print(spa)
    print(smoothed)

    # are the inputs exogenous? The reel speeds and current set points respond to the
    # tensions (the test finds feedback), so an open-loop subspace model is a description of
    # this record rather than of the plant alone; the closed-loop methods would be the
    # consistent choice (docs/closed_loop.md)
    feedback = sysid.check_feedback(est, lags=10)
    print(feedback)

    # a subspace model, checked against the non-parametric estimate and on validation data
    with warnings.catch_warnings():
        warnings.simplefilter("error", sysid.ExcitationWarning)
        warnings.simplefilter("ignore", sysid.FeedbackWarning)  # reported just above
        model = sysid.SubspaceEstimator(est, horizon=10).fit(order="auto")
    cmp = spa.compare(model)
    print(f"model order {model.nstates}:", cmp)
    y_sim = model.simulate(val.u)
    fit = 100 * (1 - np.linalg.norm(val.y - y_sim, axis=0)
                 / np.linalg.norm(val.y - val.y.mean(axis=0), axis=0))
    y_back = val.trend.add_outputs(y_sim)  # the simulation in the record's original units
    print("validation fit [%]:", np.round(fit, 1))

    if plot_dir is not None:
        out = Path(plot_dir)
        out.mkdir(parents=True, exist_ok=True)
        data.plot().savefig(out / "record.png")
        coh.plot().savefig(out / "coherence.png")
        spectra.plot().figure.savefig(out / "spectra.png")
        spa.select(inputs=["S1", "I1"]).plot(models={"subspace": model}).savefig(out / "frf.png")
    return {
        "dt": dt, "data": data, "estimation": est, "validation": val, "coherence": coh,
        "strong": strong, "spectra": spectra, "correlation": corr, "spa": spa,
        "etfe": smoothed, "feedback": feedback, "model": model, "comparison": cmp, "fit": fit,
        "y_original": y_back,
    }


if __name__ == "__main__":
    args = sys.argv[1:]
    plot_dir = None
    if "--plot" in args:
        k = args.index("--plot")
        plot_dir = args[k + 1]
        del args[k : k + 2]
    main(args[0] if args else DEFAULT, plot_dir)
