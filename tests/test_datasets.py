"""The records bundled with sysid: unmodified copies of the published files (the F-16 level 2
and 3 files: whole periods cut from them, rows unchanged), loadable by name.

The SHA-256 sums are those published with the records (``_data/README.md``, typed from the
shared data description; for the two cut files, those of the cut files); a copy that was
altered, truncated or re-encoded fails here.
"""

from __future__ import annotations

import gzip
import hashlib
import re
from pathlib import Path

import numpy as np
import pytest

import sysid

DATA_DIR = Path(sysid.datasets.path("dryer")).parent
README = DATA_DIR / "README.md"


def _published_sums() -> dict[str, str]:
    return dict(
        (name, digest)
        for digest, name in re.findall(r"^\s+([0-9a-f]{64})\s+(\S+)$", README.read_text(), re.M)
    )


def test_every_bundled_file_is_listed_with_its_checksum():
    sums = _published_sums()
    files = {p.name for p in DATA_DIR.iterdir() if p.name != "README.md"}
    assert {f.removesuffix(".gz") for f in files} == set(sums)
    assert len(sums) == len(sysid.datasets.NAMES) == 8


@pytest.mark.parametrize("name", sysid.datasets.NAMES)
def test_bundled_copy_is_the_published_file_byte_for_byte(name):
    p = Path(sysid.datasets.path(name))
    raw = gzip.decompress(p.read_bytes()) if p.suffix == ".gz" else p.read_bytes()
    assert hashlib.sha256(raw).hexdigest() == _published_sums()[p.name.removesuffix(".gz")]


@pytest.mark.parametrize(
    ("name", "shape", "dt", "n_inputs"),
    [
        ("dryer", (1000, 2), 0.08, 1),
        ("robot_arm", (1024, 2), 1.0, 1),
        ("winding", (2500, 7), 0.1, 5),
        ("ballbeam", (1000, 2), 0.1, 1),
    ],
)
def test_loaders_split_the_columns_as_documented(name, shape, dt, n_inputs):
    cols = np.loadtxt(sysid.datasets.path(name))
    assert cols.shape == shape
    d = getattr(sysid.datasets, f"load_{name}")()
    assert (d.n_samples, d.n_inputs, d.n_outputs, d.dt) == (
        shape[0], n_inputs, shape[1] - n_inputs, dt)
    np.testing.assert_array_equal(np.hstack([d.u, d.y]), cols)


def test_f16_loader_matches_the_csv_columns():
    d = sysid.datasets.load_f16()
    raw = np.genfromtxt(sysid.datasets.path("f16"), delimiter=",", skip_header=1,
                        usecols=(0, 2, 3, 4))
    np.testing.assert_array_equal(np.hstack([d.u, d.y]), raw)
    assert d.dt == 1 / 400 and d.input_units == ["N"]
    # 9 periods of 8192 samples of a 2-15 Hz multisine: steady-state periods repeat the input
    u = d.u[:, 0]
    np.testing.assert_allclose(u[2 * 8192 : 3 * 8192], u[3 * 8192 : 4 * 8192],
                               atol=0.05 * np.std(u))


def test_ph_loader_drops_the_time_column():
    cols = np.loadtxt(sysid.datasets.path("ph"))
    d = sysid.datasets.load_ph()
    assert cols.shape == (2001, 4) and (d.n_inputs, d.n_outputs, d.dt) == (2, 1, 10.0)
    np.testing.assert_array_equal(np.hstack([d.u, d.y]), cols[:, 1:])
    np.testing.assert_array_equal(cols[:, 0], np.arange(1, 2002))


@pytest.mark.parametrize(("name", "periods"), [("f16_level3", 3), ("f16_level2", 2)])
def test_cut_f16_records_are_whole_steady_state_periods(name, periods):
    d = getattr(sysid.datasets, f"load_{name}")()
    assert (d.n_samples, d.n_inputs, d.n_outputs, d.dt) == (8192 * periods, 1, 3, 1 / 400)
    raw = np.genfromtxt(sysid.datasets.path(name), delimiter=",", skip_header=1,
                        usecols=(0, 2, 3, 4))
    np.testing.assert_array_equal(np.hstack([d.u, d.y]), raw)
    # the kept periods repeat the multisine (the transient first period is not among them)
    u = d.u[:, 0]
    np.testing.assert_allclose(u[:8192], u[8192:16384], atol=0.05 * np.std(u))
    y = d.y[:, 1]
    assert np.std(y[:8192] - y[8192:16384]) < 0.2 * np.std(y)


def test_unknown_name_lists_the_bundled_ones():
    with pytest.raises(ValueError, match="dryer, robot_arm, winding, f16, f16_level3"):
        sysid.datasets.path("flutter")


def test_every_record_has_a_loader():
    for name in sysid.datasets.NAMES:
        assert callable(getattr(sysid.datasets, f"load_{name}"))
