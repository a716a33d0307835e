"""Real measured records bundled with sysid (unmodified copies; see ``_data/README.md``).

=============  ==================================  ===========================================
name           record                              file
=============  ==================================  ===========================================
``dryer``      laboratory hair dryer (DaISy):      ``dryer.dat``; 1000 samples, dt = 0.08 s,
               heater voltage -> air temperature   SLICOT's identification example
``robot_arm``  flexible robot arm (DaISy):         ``robot_arm.dat.gz``; 1024 samples, sample
               reaction torque -> acceleration     time not given by the source
``winding``    industrial winding process          ``winding.dat.gz``; 2500 samples, dt = 0.1 s,
               (DaISy): 5 inputs -> 2 tensions     columns S1 S2 S3 I1 I3 T1 T3
``f16``        F-16 ground vibration test, level   ``F16Data_FullMSine_Level1.csv.gz``; 73728
               1 (nonlinearbenchmark.org): shaker  samples at 400 Hz, 9 periods of a 2-15 Hz
               force -> three accelerations        multisine (the first is transient)
``f16_level3`` F-16, level 3 (36.8 N RMS,          ``..._Level3_periods2-4.csv.gz``: periods 2-4
               nonlinear), estimation              of the record (24576 samples; rows cut)
``f16_level2`` F-16, level 2 (24.6 N RMS),         ``..._Level2_Validation_periods2-3.csv.gz``:
               validation                          periods 2-3 (16384 samples; rows cut)
``ph``         pH neutralisation (DaISy,           ``pHdata.dat.gz``; 2001 samples, dt = 10 s
               simulated): acid, base flow -> pH
``ballbeam``   ball and beam (DaISy): beam angle   ``ballbeam.dat.gz``; 1000 samples, dt = 0.1
               -> ball position                    s; an unstable (integrating) plant
=============  ==================================  ===========================================

:func:`path` gives the file (``numpy.loadtxt`` and :meth:`sysid.IOData.from_csv` read the
compressed ones directly); ``load_<name>()`` returns the record as :class:`sysid.IOData`.
The two F-16 level 2/3 files keep only some periods of the published records (the rows
unchanged); every other file is the published file.
"""

from __future__ import annotations

from pathlib import Path

from .iodata import IOData

__all__ = [
    "path",
    "load_dryer",
    "load_robot_arm",
    "load_winding",
    "load_f16",
    "load_f16_level3",
    "load_f16_level2",
    "load_ph",
    "load_ballbeam",
    "NAMES",
]

_DIR = Path(__file__).parent / "_data"
_FILES = {
    "dryer": "dryer.dat",
    "robot_arm": "robot_arm.dat.gz",
    "winding": "winding.dat.gz",
    "f16": "F16Data_FullMSine_Level1.csv.gz",
    "f16_level3": "F16Data_FullMSine_Level3_periods2-4.csv.gz",
    "f16_level2": "F16Data_FullMSine_Level2_Validation_periods2-3.csv.gz",
    "ph": "pHdata.dat.gz",
    "ballbeam": "ballbeam.dat.gz",
}
NAMES = tuple(_FILES)


def path(name: str) -> str:
    """Filesystem path of a bundled record.

    Examples
    --------
    >>> import sysid
    >>> sysid.datasets.path("dryer").endswith("dryer.dat")
    True
    >>> sysid.datasets.NAMES
    ('dryer', 'robot_arm', 'winding', 'f16', 'f16_level3', 'f16_level2', 'ph', 'ballbeam')
    """
    if name not in _FILES:
        raise ValueError(f"unknown data set {name!r}; bundled: {', '.join(NAMES)}")
    return str(_DIR / _FILES[name])


def _columns(name: str):  # type: ignore[no-untyped-def]
    import numpy as np

    return np.loadtxt(path(name))


def _one_in_one_out(name: str, dt: float, input_name: str, output_name: str) -> IOData:
    """A bundled two-column record (input, output) as :class:`IOData`."""
    d = _columns(name)
    return IOData(u=d[:, :1], y=d[:, 1:], dt=dt, input_names=[input_name],
                  output_names=[output_name])


def load_dryer() -> IOData:
    """The hair-dryer record as :class:`sysid.IOData` (u: heater voltage, y: temperature).

    Examples
    --------
    >>> import sysid
    >>> sysid.datasets.load_dryer()
    IOData: 1000 samples, 1 input, 1 output, dt = 0.08 s
    """
    return _one_in_one_out("dryer", 0.08, "heater voltage", "air temperature")


def load_robot_arm() -> IOData:
    """The flexible robot arm (u: reaction torque of the structure, y: arm acceleration).

    The source gives no sample time: ``dt`` is 1 (frequencies in rad/sample). Published
    practice: estimate on samples 1-800, validate on 801-1024.

    Examples
    --------
    >>> import sysid
    >>> sysid.datasets.load_robot_arm()
    IOData: 1024 samples, 1 input, 1 output, dt = 1 s
    """
    return _one_in_one_out("robot_arm", 1.0, "torque", "acceleration")


def load_winding() -> IOData:
    """The industrial winding process: reel speeds S1, S2, S3 and motor current set-points
    I1, I3 in; web tensions T1, T3 out; dt = 0.1 s.

    Examples
    --------
    >>> import sysid
    >>> sysid.datasets.load_winding()
    IOData: 2500 samples, 5 inputs, 2 outputs, dt = 0.1 s
    """
    d = _columns("winding")
    return IOData(u=d[:, :5], y=d[:, 5:7], dt=0.1,
                  input_names=["S1", "S2", "S3", "I1", "I3"], output_names=["T1", "T3"])


def load_f16() -> IOData:
    """The F-16 ground vibration test, level 1 (12.4 N RMS, close to linear): shaker force
    in (N), three accelerations out, fs = 400 Hz, 9 periods of 8192 samples (drop the first,
    which holds the transient). The shaker's reference voltage, an alternative input, is in
    the file (:func:`path`) as column ``Voltage``.

    Examples
    --------
    >>> import sysid
    >>> d = sysid.datasets.load_f16()
    >>> d
    IOData: 73728 samples, 1 input, 3 outputs, dt = 0.0025 s
    >>> d.output_names
    ['Acceleration1', 'Acceleration2', 'Acceleration3']
    """
    return _f16("f16")


def _f16(name: str) -> IOData:
    outputs = ["Acceleration1", "Acceleration2", "Acceleration3"]
    d = IOData.from_csv(path(name), ["Force"], outputs, dt=1 / 400)
    return IOData(d.u, d.y, d.dt, input_names=["Force"], output_names=outputs,
                  input_units=["N"])


def load_f16_level3() -> IOData:
    """The F-16 ground vibration test at level 3 (36.8 N RMS, the most nonlinear shipped
    level; the benchmark's estimation record): periods 2-4 of the 9 (24576 samples at
    400 Hz, in steady state; the transient first period and periods 5-9 are not shipped).

    Examples
    --------
    >>> import sysid
    >>> sysid.datasets.load_f16_level3()
    IOData: 24576 samples, 1 input, 3 outputs, dt = 0.0025 s
    """
    return _f16("f16_level3")


def load_f16_level2() -> IOData:
    """The F-16 ground vibration test at level 2 (24.6 N RMS; the benchmark's validation
    record for models estimated at level 3): periods 2-3 of the 9 (16384 samples at 400 Hz).

    Examples
    --------
    >>> import sysid
    >>> sysid.datasets.load_f16_level2()
    IOData: 16384 samples, 1 input, 3 outputs, dt = 0.0025 s
    """
    return _f16("f16_level2")


def load_ph() -> IOData:
    """The pH neutralisation process (DaISy, simulated, nonlinear): acid and base
    flows in, pH out; dt = 10 s (the file's first column, the time index, is dropped).

    Examples
    --------
    >>> import sysid
    >>> sysid.datasets.load_ph()
    IOData: 2001 samples, 2 inputs, 1 output, dt = 10 s
    """
    d = _columns("ph")
    return IOData(u=d[:, 1:3], y=d[:, 3:], dt=10.0, input_names=["acid flow", "base flow"],
                  output_names=["pH"])


def load_ballbeam() -> IOData:
    """The ball and beam (DaISy, real): beam angle in, ball position out; dt = 0.1 s. The
    plant integrates (the ball rolls while the beam is tilted), so models of it have poles on
    or just outside the unit circle.

    Examples
    --------
    >>> import sysid
    >>> sysid.datasets.load_ballbeam()
    IOData: 1000 samples, 1 input, 1 output, dt = 0.1 s
    """
    return _one_in_one_out("ballbeam", 0.1, "beam angle", "ball position")
