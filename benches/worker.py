"""One benchmark measurement in a fresh process: load a case, identify, report JSON.

Run by benches/run.py with the interpreter of the tool's environment (the sysid development
venv for sysid and NumPy, benches/.venv-peers for sippy-unipi and nfoursid). Prints one JSON
line: wall time of the identification alone, the process's peak resident memory and its
resident memory just before identification (interpreter, imports and data), and the
identified poles.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import sys
import time
import traceback

import numpy as np


def rss_mb() -> float:
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE") / 2**20


def peak_mb() -> float:
    """Peak resident memory of this process image (VmHWM; ru_maxrss would include the
    parent's memory at fork time, which Linux carries across exec)."""
    with open("/proc/self/status") as f:
        for line in f:
            if line.startswith("VmHWM:"):
                return int(line.split()[1]) / 1024.0
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def po_moesp_a(l_mat: np.ndarray, m: int, l: int, i: int, order: int) -> np.ndarray:
    """A from the triangular factor (rows [U_f; U_p; Y_p; Y_f]) by PO-MOESP (Verhaegen 1994):
    the Y_f rows of L in the columns of the past data span the extended observability
    matrix."""
    fm, pp = i * m, i * (m + l)
    l32 = l_mat[fm + pp :, fm : fm + pp]
    uu = np.linalg.svd(l32, full_matrices=False)[0][:, :order]
    return np.linalg.lstsq(uu[:-l], uu[l:], rcond=None)[0]


def hankel_numpy(u: np.ndarray, y: np.ndarray, i: int) -> np.ndarray:
    """Plain NumPy baseline: the explicit block-Hankel matrix and one dense QR."""
    n = y.shape[0]
    cols = n - 2 * i + 1

    def blocks(x: np.ndarray, start: int) -> np.ndarray:
        return np.vstack([x[start + j : start + j + cols].T for j in range(i)])

    h = np.vstack([blocks(u, i), blocks(u, 0), blocks(y, 0), blocks(y, i)])
    r = np.linalg.qr(h.T, mode="r")
    return r.T


def run_sysid(u, y, i, order, compressor):
    """The whole identification through the public API (PO-MOESP, A B C D K)."""
    import sysid

    t0 = time.perf_counter()
    est = sysid.SubspaceEstimator(sysid.IOData(u=u, y=y), horizon=i, compressor=compressor)
    t1 = time.perf_counter()
    model = est.fit(order=order)
    abcd = tuple(np.asarray(x) for x in (model.A, model.B, model.C, model.D))
    return abcd, {"source": est.factor.source, "compress_seconds": t1 - t0,
                  "fit_seconds": time.perf_counter() - t1}


def run_numpy(u, y, i, order):
    return (po_moesp_a(hankel_numpy(u, y, i), u.shape[1], y.shape[1], i, order),), {}


def run_sippy(u, y, i, order):
    try:
        from sippy import system_identification
    except ImportError:  # sippy-unipi >= 1.0 installs the package as sippy_unipi
        from sippy_unipi import system_identification

    sysid_ = system_identification(
        y.T, u.T, "N4SID", SS_fixed_order=order, SS_f=i, SS_p=i, SS_threshold=0.0
    )
    return tuple(np.asarray(x) for x in (sysid_.A, sysid_.B, sysid_.C, sysid_.D)), {}


def run_nfoursid(u, y, i, order):
    import pandas as pd
    from nfoursid.nfoursid import NFourSID

    cols_u = [f"u{j}" for j in range(u.shape[1])]
    cols_y = [f"y{j}" for j in range(y.shape[1])]
    df = pd.DataFrame(np.hstack([u, y]), columns=cols_u + cols_y)
    nf = NFourSID(df, output_columns=cols_y, input_columns=cols_u, num_block_rows=i)
    nf.subspace_identification()
    ss, _ = nf.system_identification(rank=order)
    return tuple(np.asarray(x) for x in (ss.a, ss.b, ss.c, ss.d)), {}


def validation_fit(abcd, path: str, m: int) -> float:
    """Simulation fit on a fresh record of the same system, 100 (1 - |y - yhat| / |y - mean|),
    averaged over outputs."""
    a, b, c, d = abcd
    z = np.load(path)
    u, y = z[:, :m], z[:, m:]
    x = np.zeros(a.shape[0])
    yh = np.empty_like(y)
    for t in range(len(u)):
        yh[t] = c @ x + d @ u[t]
        x = a @ x + b @ u[t]
    err = np.linalg.norm(y - yh, axis=0) / np.linalg.norm(y - y.mean(axis=0), axis=0)
    return float(np.mean(100 * (1 - err)))


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--tool", required=True)
    ap.add_argument("--data", required=True)
    ap.add_argument("--m", type=int, required=True)
    ap.add_argument("--horizon", type=int, required=True)
    ap.add_argument("--order", type=int, required=True)
    ap.add_argument("--memory-limit-gb", type=float, default=16.0)
    ap.add_argument("--validation", default=None, help="record for the validation fit")
    ap.add_argument("--repeat", type=int, default=1,
                    help="identify this many times in the process; `seconds` is the first "
                         "(cold: lazy imports, thread pool start), `warm_seconds` the best "
                         "of the others")
    args = ap.parse_args()
    lim = int(args.memory_limit_gb * 2**30)
    resource.setrlimit(resource.RLIMIT_AS, (lim, lim))
    out: dict = {"tool": args.tool}
    try:
        if args.tool.startswith("sysid"):
            import sysid  # noqa: F401  (imports count in the baseline)
        elif args.tool == "sippy":
            try:
                import sippy  # noqa: F401
            except ImportError:
                import sippy_unipi  # noqa: F401
        elif args.tool == "nfoursid":
            import nfoursid  # noqa: F401
            import pandas  # noqa: F401
        z = np.load(args.data)
        u, y = np.ascontiguousarray(z[:, : args.m]), np.ascontiguousarray(z[:, args.m :])
        del z
        # reset the peak (VmHWM) so that loading the data does not count as the tool's peak
        try:
            with open("/proc/self/clear_refs", "w") as f:
                f.write("5")
        except OSError:
            pass
        out["baseline_mb"] = rss_mb()
        t0 = time.perf_counter()
        if args.tool == "sysid-auto":
            abcd, info = run_sysid(u, y, args.horizon, args.order, "auto")
        elif args.tool == "sysid-correlation":
            abcd, info = run_sysid(u, y, args.horizon, args.order, "correlation")
        elif args.tool == "sysid-qr":
            abcd, info = run_sysid(u, y, args.horizon, args.order, "qr")
        elif args.tool == "numpy-qr":
            abcd, info = run_numpy(u, y, args.horizon, args.order)
        elif args.tool == "sippy":
            abcd, info = run_sippy(u, y, args.horizon, args.order)
        elif args.tool == "nfoursid":
            abcd, info = run_nfoursid(u, y, args.horizon, args.order)
        else:
            raise SystemExit(f"unknown tool {args.tool}")
        out["seconds"] = time.perf_counter() - t0
        out["peak_mb"] = peak_mb()
        warm = []
        for _ in range(args.repeat - 1):
            t1 = time.perf_counter()
            if args.tool.startswith("sysid"):
                run_sysid(u, y, args.horizon, args.order, args.tool.split("-", 1)[1])
            elif args.tool == "sippy":
                run_sippy(u, y, args.horizon, args.order)
            else:
                break
            warm.append(time.perf_counter() - t1)
        if warm:
            out["warm_seconds"] = min(warm)
        if args.validation and len(abcd) == 4:
            out["fit"] = validation_fit(abcd, args.validation, args.m)
        ev = np.linalg.eigvals(abcd[0])
        out["poles"] = [[float(z.real), float(z.imag)] for z in ev]
        out.update(info)
        out["ok"] = True
    except BaseException as exc:  # noqa: BLE001 - a failing peer is a result, report it
        out["ok"] = False
        msg = f"{type(exc).__name__}: {exc}"
        out["error"] = msg.splitlines()[0][:200] if msg.strip() else traceback.format_exc()[-200:]
    out.setdefault("peak_mb", peak_mb())
    sys.stdout.write(json.dumps(out) + "\n")


if __name__ == "__main__":
    main()
