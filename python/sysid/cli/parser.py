"""The ``sysid`` command's argument parser: its subcommands and their options."""

from __future__ import annotations

import argparse

from .demo_command import _demo
from .identify_command import _identify

#: the command's description in ``sysid --help``
USAGE = """The ``sysid`` command line.

``sysid identify DATA.csv --inputs U --outputs Y --report OUT/``
    Identify a state-space model from a CSV file: split into estimation and validation
    parts, compress once, sweep the orders, fit the chosen order, validate, and write the
    model (JSON), the tables (CSV) and the plots (PNG) with an HTML page that shows them.
``sysid demo [--report DIR]``
    The same on the bundled hair-dryer record (estimation samples 1-500, validation
    501-1000, horizon 15, order auto); prints a short summary.
"""


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="sysid", description=USAGE,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = parser.add_subparsers(dest="command", required=True)
    demo = sub.add_parser("demo", help="identify the bundled hair-dryer record")
    demo.add_argument("--report", default="report", help="report directory (default ./report)")
    demo.add_argument("--quiet", action="store_true", help="no progress lines on stderr")
    demo.set_defaults(func=_demo)
    ide = sub.add_parser("identify", help="identify a model from a CSV file")
    ide.add_argument("data", help="CSV file (header row of column names, numeric rows) or "
                     "Parquet file; files over 8 MB are read in blocks with a progress bar")
    ide.add_argument("--inputs", default="", help="input columns, comma separated")
    ide.add_argument("--outputs", required=True, help="output columns, comma separated")
    ide.add_argument("--order", default="auto", help="model order or 'auto' (default)")
    ide.add_argument("--method", default="auto",
                     help="auto (default: sysid.identify chooses the family, order and "
                          "feedthrough on held-out parts of the estimation data, when --order "
                          "is auto and neither --horizon nor --uncertainty bootstrap is given "
                          "and there are --inputs; else moesp, and the progress says so), or "
                          "one subspace method: moesp, ordinary-moesp, pi-moesp, n4sid, cva; "
                          "closed loop: pbsid or ssarx")
    ide.add_argument("--feedthrough", choices=("no", "yes", "auto"), default=None,
                     help="with a subspace --method: estimate D (yes), not (no) or decide "
                          "from held-out parts of the estimation data (auto); default, as "
                          "every sysid estimator: no with a given --order, auto with --order "
                          "auto; --method auto decides it itself")
    ide.add_argument("--horizon", type=int, default=None, help="past/future horizon")
    ide.add_argument("--split", default="0.5",
                     help="estimation part: fraction (0.5) or sample count (500); 1 = all")
    ide.add_argument("--dt", type=float, default=None,
                     help="sample time in seconds (a time column of the file must agree)")
    ide.add_argument("--time", default=None,
                     help="time column (sample time from its steps, in the unit of its "
                          "header, units row or name: Time [ms], time_ms; seconds without)")
    ide.add_argument("--resample", default=None, metavar="median|SECONDS",
                     help="a time column with gaps or jitter (a logger's stamps): interpolate "
                          "the record linearly onto a uniform grid of this sample time (median: "
                          "the stamps' median spacing); noted in the report")
    ide.add_argument("--resample-gap", dest="resample_gap", type=float, default=5.0,
                     help="with --resample: longest interval between stamps bridged, in sample "
                          "times (default 5); a longer one is refused, naming it")
    ide.add_argument("--fill-gaps", dest="fill_gaps", type=int, default=None, metavar="N",
                     help="missing cells (empty or nan) of the inputs and outputs: fill runs "
                          "of at most N samples of a channel linearly between the samples "
                          "around them, and drop rows at the file's start or end that miss "
                          "one; a longer run is refused, naming it (default: any missing "
                          "cell is refused); noted in the report")
    ide.add_argument("--detrend", choices=("auto", "none", "mean", "linear"), default="auto",
                     help="remove the estimation part's means (or lines) first; recorded in "
                          "the model. auto (default): none when sysid.identify runs (it "
                          "removes the offsets itself and restores them in the saved "
                          "model), else the means (a linear model has no constant term; "
                          "none fits the raw data, as SLICOT, and warns when an offset "
                          "dominates)")
    ide.add_argument("--delimiter", default=None, help="field separator (default: guessed)")
    ide.add_argument("--decimal", choices=(".", ","), default=".",
                     help="decimal mark of the numbers: . (default) or , (decimal commas, as "
                          "European loggers write them: 0,25;1,5 with a semicolon between "
                          "fields)")
    ide.add_argument("--report", required=True, help="output directory")
    ide.add_argument("--uncertainty", choices=("none", "bootstrap"), default="none",
                     help="pole standard deviations in the report from a residual bootstrap")
    ide.add_argument("--n-boot", dest="n_boot", type=int, default=100,
                     help="bootstrap records (default 100)")
    ide.add_argument("--compressor", choices=("auto", "qr", "correlation"), default="auto",
                     help="data compression: auto (default: fast, exact path when the data "
                          "are ill-conditioned), qr (exact), correlation (fast)")
    ide.add_argument("--quiet", action="store_true", help="no progress lines on stderr")
    ide.add_argument("--progress", action="store_true",
                     help="progress bars (rate, time left) even when stderr is not a terminal")
    ide.set_defaults(func=_identify)
    return parser

