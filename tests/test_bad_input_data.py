"""Bad input to the data, FRD, serialisation, report, grey-box and recursive entry points:
a sysid error naming the problem and the fix, never a raw AttributeError, KeyError or
third-party error, a silently ignored argument or a misleading message."""

from __future__ import annotations

import numpy as np
import pytest

import sysid

from conftest import first_order_record


@pytest.fixture(scope="module")
def record():
    m, u, y, d = first_order_record()
    return m, u, y, d


# ---- 1. raw AttributeError --------------------------------------------------------------

@pytest.mark.parametrize("call", [
    lambda u: sysid.despike(u),
    lambda u: sysid.drop_quiet(u),
    lambda u: sysid.select_mask(u, np.ones(len(u), bool)),
    lambda u: sysid.select_mode(u, np.ones(len(u)), keep=1),
    lambda u: sysid.check_offsets(u),
])
def test_preprocessing_refuses_an_array_for_a_record(record, call):
    _, u, _, _ = record
    with pytest.raises(sysid.DataError, match="takes an IOData record"):
        call(u)


def test_merge_of_a_list_says_how_to_call_it(record):
    d = record[3]
    with pytest.raises(sysid.DataError, match=r"records\[0\]\.merge"):
        sysid.IOData.merge([d, d])


def test_frd_refuses_a_model_without_freqresp(record):
    m = record[0]
    with pytest.raises(sysid.DataError, match="freqresp"):
        sysid.FRD.from_model("x", [1.0])
    matplotlib = pytest.importorskip("matplotlib")
    matplotlib.use("Agg")
    frd = sysid.FRD.from_model(m, np.linspace(0.1, 30, 50))
    with pytest.raises(sysid.DataError, match="models must be a model with freqresp"):
        frd.plot(models="x")


def test_register_model_refuses_a_non_class():
    with pytest.raises(sysid.DataError, match="takes a model class"):
        sysid.register_model(5)


def test_report_refuses_a_selection_that_is_not_an_order_sweep(record, tmp_path):
    m, _, _, d = record
    with pytest.raises(sysid.DataError, match=r"result\.model"):
        sysid.report(m, d, tmp_path / "r", selection=sysid.identify(d))
    with pytest.raises(sysid.DataError, match="selection must be an order sweep"):
        sysid.report(m, d, tmp_path / "r", selection="aic")
    with pytest.raises(sysid.DataError, match="which must be"):
        sysid.report(m, d, tmp_path / "r", which="foo")
    assert not (tmp_path / "r").exists()


# ---- 2. other raw exceptions ------------------------------------------------------------

def test_from_pandas_names_a_missing_experiment_or_time_column(record):
    pd = pytest.importorskip("pandas")
    _, u, y, _ = record
    df = pd.DataFrame({"u": u[:, 0], "y": y[:, 0]})
    with pytest.raises(sysid.DataError, match="experiment column 'zz' is not in"):
        sysid.IOData.from_pandas(df, ["u"], ["y"], dt=0.1, experiment="zz")
    with pytest.raises(sysid.DataError, match="time column 't' is not in"):
        sysid.IOData.from_pandas(df, ["u"], ["y"], time="t")


def test_from_mat_of_a_garbage_file_names_the_file(tmp_path):
    f = tmp_path / "g.mat"
    f.write_bytes(b"garbage")
    with pytest.raises(sysid.DataError, match="g.mat is not a readable MATLAB"):
        sysid.IOData.from_mat(f)


def test_from_npz_of_other_files_never_suggests_pickle(record, tmp_path):
    _, u, _, d = record
    (tmp_path / "g.npz").write_bytes(b"garbage")
    np.save(tmp_path / "a.npy", u)
    np.savez(tmp_path / "b.npz", u=u)
    for name in ("g.npz", "a.npy", "b.npz"):
        with pytest.raises(sysid.DataError, match="is not a sysid .npz record") as e:
            sysid.IOData.from_npz(tmp_path / name)
        assert "pickle" not in str(e.value)
    d.to_npz(tmp_path / "ok.npz")
    assert sysid.IOData.from_npz(tmp_path / "ok.npz") == d


def test_from_npz_of_an_empty_or_cut_off_file_says_so(record, tmp_path):
    _, _, _, d = record
    d.to_npz(tmp_path / "ok.npz")
    whole = (tmp_path / "ok.npz").read_bytes()
    (tmp_path / "empty.npz").write_bytes(b"")
    (tmp_path / "cut.npz").write_bytes(whole[: len(whole) // 2])
    for name in ("empty.npz", "cut.npz"):
        with pytest.raises(sysid.DataError, match=f"{name} is empty or cut off"):
            sysid.IOData.from_npz(tmp_path / name)


def test_nlgreybox_simulate_checks_the_input_array():
    g = sysid.NonlinearGreyBox(lambda t, x, u, p: [-x[0] + u[0]], lambda t, x, u, p: [x[0]],
                               {"K": 1.0}, nx=1)
    with pytest.raises(sysid.ShapeError, match="u must be 1-D or 2-D"):
        g.simulate(np.zeros((2, 3, 4)), dt=0.1)
    with pytest.raises(sysid.DataError, match="dt must be a positive number"):
        g.simulate(np.zeros(5), dt="x")


def test_frd_refuses_non_numeric_responses(record):
    m = record[0]
    w = np.linspace(0.1, 30, 100)
    with pytest.raises(sysid.DataError, match="response must be a numeric"):
        sysid.FRD(w, ["a"] * 100)
    with pytest.raises(sysid.DataError, match="other must be a model with freqresp"):
        sysid.FRD.from_model(m, w).compare("x")


def test_experiment_by_a_non_integer_says_how_experiments_are_indexed(record):
    d = record[3]
    for k in ("a", 1.5, ["a"]):
        with pytest.raises(sysid.DataError, match="indexed by their position"):
            d.experiment(k)
    assert d.experiment(0) == d


def test_recursive_run_of_a_record_says_what_run_takes(record):
    d = record[3]
    # a record runs as its arrays (tests/test_recursive.py); the arrays without y, or a
    # record and y, are refused naming both forms
    with pytest.raises(sysid.DataError, match=r"run\(data\) for a record.*run\(u, y\)"):
        sysid.RecursiveARX(2, 2, 1).run(d.u, None)
    with pytest.raises(sysid.DataError, match=r"run\(data\) or run\(data.u, data.y\)"):
        sysid.RecursiveARX(2, 2, 1).run(d, d.y)


# ---- 3. wrong or misleading messages ----------------------------------------------------

def test_model_from_dict_of_a_models_own_to_dict_points_to_the_right_pair(record):
    m = record[0]
    with pytest.raises(sysid.DataError, match=r"StateSpaceModel\.from_dict") as e:
        sysid.model_from_dict(m.to_dict())
    assert "found None" not in str(e.value)
    back = sysid.model_from_dict(sysid.model_to_dict(m))
    assert np.array_equal(back.A, m.A) and back.dt == m.dt
    assert np.array_equal(type(m).from_dict(m.to_dict()).A, m.A)


def test_writing_into_a_missing_folder_names_the_users_path(record, tmp_path):
    m, _, _, d = record
    target = tmp_path / "missing" / "m.json"
    with pytest.raises(FileNotFoundError, match="folder .* does not exist") as e:
        sysid.save_model(m, target)
    assert str(target) in str(e.value) and ".tmp" not in str(e.value)
    with pytest.raises(FileNotFoundError, match="does not exist") as e:
        d.to_csv(tmp_path / "missing" / "x.csv")
    assert "x.csv" in str(e.value) and ".tmp" not in str(e.value)


def test_arxregul_refuses_a_constant_record_first():
    n = 400
    const = sysid.IOData(u=np.ones((n, 1)), y=np.ones((n, 1)), dt=0.1)
    with pytest.raises(sysid.DataError, match="input u0 is 1 in every sample: arxregul"):
        sysid.arxregul(const, 2, 5, 1)


# ---- 4. silently ignored or unchecked arguments -----------------------------------------

def _tank(**kw):
    return sysid.NonlinearGreyBox(lambda t, x, u, p: [-x[0] / p.tau + p.K * u[0] / p.tau],
                                  lambda t, x, u, p: [x[0]], {"K": 1.0, "tau": 0.5}, **kw)


@pytest.mark.parametrize("kw, phrase", [
    ({"dt": 1.0}, "differs from the data's dt"),
    ({"ninputs": 3}, "the structure has 3 input"),
    ({"noutputs": 3}, "the structure has 3 output"),
])
def test_nlgreybox_refuses_sizes_that_contradict_the_data(record, kw, phrase):
    d = record[3]
    with pytest.raises(sysid.DataError, match=phrase):
        sysid.greyest(d, _tank(nx=1, **kw), max_iter=3)


@pytest.mark.parametrize("kw, phrase", [
    ({"nx": 1.5}, "nx must be a positive integer"),
    ({"nx": 1, "x0_free": "yes"}, "x0_free must be True, False"),
    ({"nx": 1, "dt": -1.0}, "dt must be a positive number"),
    ({"nx": 1, "ninputs": 1.5}, "ninputs must be"),
])
def test_nlgreybox_refuses_bad_constructor_arguments(kw, phrase):
    with pytest.raises(sysid.DataError, match=phrase):
        _tank(**kw)


@pytest.mark.parametrize("call, phrase", [
    (lambda d: sysid.despike(d, dropout=float("nan")), "dropout must be the finite"),
    (lambda d: sysid.drop_quiet(d, threshold=float("nan")), "threshold must be a finite"),
    (lambda d: sysid.drop_quiet(d, threshold=-1), "threshold must be a finite"),
    (lambda d: sysid.decimate(d, 2, order=0), "order must be an integer between 1 and 30"),
])
def test_preprocessing_refuses_bad_settings(record, call, phrase):
    with pytest.raises(sysid.DataError, match=phrase):
        call(record[3])


@pytest.mark.parametrize("kw, phrase", [
    ({"dt": -1}, "dt must be a positive number"),
    ({"retries": -1}, "retries must be an integer >= 0"),
    ({"flush_every": 0}, "flush_every must be a positive integer"),
    ({"progress": "x"}, "progress must be True, False or None"),
    ({"record_id": 5}, "record_id must be the name"),
    ({"inputs": ["nope"]}, "inputs say how a table becomes a record"),
])
def test_identify_many_refuses_bad_or_ignored_arguments(record, tmp_path, kw, phrase):
    d = record[3]
    with pytest.raises(sysid.DataError, match=phrase):
        sysid.identify_many([d], out=tmp_path / "t.parquet", workers=0, **kw)
    assert not (tmp_path / "t.parquet").exists()


def test_recursive_subspace_checks_dt_and_chunk_shapes(record):
    _, u, y, _ = record
    with pytest.raises(sysid.DataError, match="dt must be a positive number"):
        sysid.RecursiveSubspace(1, 5, dt=0)
    uu, yy = np.c_[u, u], np.c_[y, y]
    with pytest.raises(sysid.ShapeError, match="looks transposed"):
        sysid.RecursiveSubspace(1, 5).update(uu.T, yy.T)
    rs = sysid.RecursiveSubspace(1, 5)
    rs.update(u[:200], y[:200])
    with pytest.raises(sysid.ShapeError, match="looks transposed"):
        rs.update(u[200:].T, y[200:].T)
    assert rs.update(u[200:], y[200:]) is not None
