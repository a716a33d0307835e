"""Real records: sysid's automatic path and defaults against peers and a plain NumPy/SciPy
reference, scored on held-out validation data.

    .venv/bin/python benches/realdata.py                 # every record (several minutes)
    .venv/bin/python benches/realdata.py --records dryer robot_arm
    .venv/bin/python benches/realdata.py --no-peers      # without SIPPY / nfoursid
    .venv/bin/python benches/realdata.py --split reversed --no-peers --records dryer ...
    .venv/bin/python benches/realdata.py --unshipped DIR # DaISy records not shipped (below)
    .venv/bin/python benches/realdata.py --nonlinear-records DIR --no-peers  # (below)
    .venv/bin/python benches/realdata.py --more-records DIR  # six more records (below)

Records (``/work/shared/data``, see its README; the DaISy records and the F-16 ground
vibration test). Splits: the README's where it gives one (dryer 1:500 / 501:1000, robot arm
1:800 / 801:1024, heat-flux wall 1:1200 / 1201:1680), otherwise the first 2/3 for estimation
and the last 1/3 for validation; the F-16 levels are estimated on periods 2-3 of their own
file (16 384 samples, the first period holds the transient) and validated on period 2 of the
level-2 validation file. pH is nonlinear and included as such; the ball and beam is integrating
and used as recorded (not differenced); the distillation column uses its noise-free channels
(inputs 2-6, outputs 22-24: 60 / 30 samples).

``--split`` changes the splits, a proxy for records the project never sees (does a choice
hold up when estimation and validation data trade places?): ``default`` is the above;
``reversed`` estimates on the *last* part of the same length as the default estimation part
and validates on the first (dryer 501:1000 / 1:500, robot arm 225:1024 / 1:224, the 2/3
records their last 2/3 / first 1/3); ``swap`` estimates on the default validation part and
validates on the default estimation part (a short estimation record). The F-16 levels keep
their split under every ``--split`` (a separate validation file; leave them out with
``--records``). Another split writes ``results/realdata_<split>.md`` unless ``--out`` is given,
and ``--reuse`` takes only rows of the same split. ``--unshipped DIR`` runs instead DaISy
records that the project does not ship and no choice in sysid was made on (``UNSHIPPED``:
heat exchanger, heating system, glass furnace, evaporator, CD player arm, industrial dryer,
steam generator, power plant; first 2/3 / last 1/3), read from a directory holding the
collection's ``.dat`` files, into ``results/realdata_unshipped[_<split>].md``.
``--nonlinear-records DIR`` runs the linear tools on four nonlinear benchmark records the
project does not ship either (Silverbox, Wiener-Hammerstein 2009, cascaded tanks, EMPS: the
splits and files of ``benches/nonlinear_unshipped.py``, training cut to 20 000 samples, each
validated on its benchmark test record under every ``--split``), into
``results/realdata_nonlinear_records.md``: the best linear approximation of each.
``--more-records DIR`` runs six more records (five from outside the DaISy collection) that the
project does not ship (``MORE``), each read from ``DIR/<name>.npz`` (arrays ``u``, ``y``), into
``results/realdata_more[_<split>].md``: the Box-Jenkins gas furnace (series J, 296 samples;
a copy at GitHub WizardKingZ/time_series_outlier_detection ``gas-furnace.csv``), a DC-DC buck
converter and a DC motor driving a generator (GitHub wilsonrljr/sysidentpy-data,
``datasets/buck/buck_id.csv`` validated on ``buck_valid.csv``, and ``datasets/generator/
x_cc.csv``, ``y_cc.csv`` every 500th sample, as SysIdentPy's examples thin them), and the
magneto-rheological damper and industrial robot arm of MATLAB's System Identification
Toolbox examples (copies in GitHub gsmfnc/LPV_SysId, ``noise_simulations/autoencoders/
Magneto.mat``, its estimation and validation parts joined back into one record, and
``RobotArm.mat``: ``U, Y`` validated on ``U_val, Y_val``), and DaISy's flexible structure (2
inputs, 28 outputs, 8 523 samples; a copy at GitHub robotsorcerer/FARNN,
``data/flexibleStructure.mat``: inputs columns 1-2, outputs 3-30). The records of one file take the
first 2/3 / last 1/3 split (every ``--split`` applies); the two with a separate validation
record keep it under every ``--split``, as the F-16 levels do.
``--fresh-records DIR`` runs, the same way (``FRESH``, ``DIR/<name>.npz``, first 2/3 / last
1/3), into ``results/realdata_fresh[_<split>].md``, seven records first used on 2026-12-05:
the coupled electric drives benchmark (Wigren and Schoukens, 2017; copies in GitHub
Agnibha-31/AURA-Membership-Function-Neuro-Fuzzy-Process-Control-Automation, ``Coupled
Eletric Drives Datasets/DATAPRBS.MAT`` ``u1, z1`` and ``DATAUNIF.MAT`` ``u11, z11``, 500
samples each, 20 ms), a TCLab heater step test (GitHub jckantor/cbe30338-book,
``tclab/Step_Test_Data.csv``: ``Q1`` -> ``T1, T2``, 801 samples, 1 s) and a step test of the
HSM150 two-motor bench (GitHub malik-robert/HSM150-data, ``Data/Identification/
idf_pos_0.065_2.mat``, ``data`` column 5 (input torque) -> column 4 (speed), 20 000 samples,
1 ms), and three AutomationShield lab devices (GitHub gergelytakacs/AutomationShield,
``matlab/examples/``: ``FloatShield/PRBS_R4.mat`` ``u -> y``, fan to ball height, 7 200
samples, 25 ms; ``MotoShield/aprbsResult.mat`` ``u -> y``, voltage to speed, 4 801 samples,
20 ms; ``MagnetoShield/MagnetoShield_ID_Data.mat`` ``result`` column 2 -> columns 1, 3,
voltage to position and current under PID feedback, 7 500 samples, 3.25 ms).
``--fresh2-records DIR`` (``FRESH2``, results/realdata_fresh2[_<split>].md): the second
sweep's four records (a TCLab log of two heaters under PID, a catchment's daily rainfall and
evaporation to flow, a balancing robot car's 2 ms log, two tail-sitter UAV flights); their
sources, SHA-256 and how each ``.npz`` is made: results/realdata_fresh.md.
``--fresh3-records DIR`` (``FRESH3``, results/realdata_fresh3_table[_<split>].md): the third
sweep's four records (a test building's heating, a level pilot plant, a hydro generator's
excitation step test, an aircraft's lateral flight test); sources, SHA-256, how each ``.npz``
is made and the findings: results/realdata_fresh3.md.
``--fresh4-records DIR`` (``FRESH4``, results/realdata_fresh4_table[_<split>].md): the fourth
sweep's three records (a car's acceleration, a servo-hydraulic actuator, a quadrotor on a test
bed); sources, SHA-256, how each ``.npz`` is made and the findings: results/realdata_fresh4.md.
``--fresh5-records DIR`` (``FRESH5``, results/realdata_fresh5_table[_<split>].md): the fifth
sweep's records (a battery cell's pulse test, a car's lateral force, a ship model's zigzag);
sources, SHA-256, how each ``.npz`` is made and the findings: results/realdata_fresh5.md.
``--fresh6-records DIR`` (``FRESH6``, results/realdata_fresh6_table[_<split>].md): the sixth
sweep's records (a heated air duct at two damper settings, a propeller-driven pendulum);
sources, SHA-256, how each ``.npz`` is made and the findings: results/realdata_fresh6.md.
``--fresh7-records DIR`` (``FRESH7``, results/realdata_fresh7_table[_<split>].md): the seventh
sweep's records (a four-tank process under feedback, its valves set for a non-minimum-phase and
a minimum-phase zero: two pumps to two levels); sources, SHA-256, how each ``.npz`` is made and
the findings: results/realdata_fresh7.md.
``--fresh8-records DIR`` (``FRESH8``, results/realdata_fresh8_table[_<split>].md): the eighth
sweep's records (a five-storey test tower shaken by its hybrid mass damper, a soft pneumatic
bending actuator, an LED lighting a photoresistor); sources, SHA-256, how each ``.npz`` is made
and the findings: results/realdata_fresh8.md.
``--fresh9-records DIR`` (``FRESH9``, results/realdata_fresh9_table[_<split>].md): the ninth
sweep's records (a single-zone building's heat pump in summer and in winter, a gantry crane's
load swing); sources, SHA-256, how each ``.npz`` is made and the findings:
results/realdata_fresh9.md.
``--fresh10-records DIR`` (``FRESH10``, results/realdata_fresh10_table[_<split>].md): the tenth
sweep's records (a rotary flexible link under a servo controller, a quadcopter on a roll rig
under cascaded PID, an irrigation canal's gate step, a wheel loader at work); sources,
SHA-256, how each ``.npz`` is made and the findings: results/realdata_fresh10.md.
``--fresh11-records DIR`` (``FRESH11``, results/realdata_fresh11_table[_<split>].md): the
eleventh sweep's records (a 2-DOF helicopter's two rotors driven open loop); sources, SHA-256,
how each ``.npz`` is made and the findings: results/realdata_fresh11.md.
``--fresh12-records DIR`` (``FRESH12``, results/realdata_fresh12_table[_<split>].md): the
twelfth sweep's records (a magnetic levitation rig under PID control, a friction damper driven
by earthquake displacements, an electromagnetic actuator's chirp test), each validated on a
second run; sources, SHA-256, how each ``.npz`` is made and the findings:
results/realdata_fresh12.md.
``--fresh13-records DIR`` (``FRESH13``, results/realdata_fresh13_table[_<split>].md): the
thirteenth sweep's records (a rotary inverted pendulum under a PD loop, a piezo steering
mirror's periodic multisine, a loudspeaker-driven chopper's sine), each validated on a second
run; sources, SHA-256, how each ``.npz`` is made and the findings: results/realdata_fresh13.md.
``--fresh14-records DIR`` (``FRESH14``, results/realdata_fresh14_table[_<split>].md): the
fourteenth sweep's records (a flexible-link robot under a lead compensator, validated on a
second sweep; a ventilator on a test lung under PI pressure control, split); sources, SHA-256,
how each ``.npz`` is made and the findings: results/realdata_fresh14.md.
``--fresh15-records DIR`` (``FRESH15``, results/realdata_fresh15_table[_<split>].md): the
fifteenth sweep's records (a shake table's one-storey model, a twin rotor's pitch, a gasoline
engine's emissions), each validated on a second run; sources, SHA-256, how each ``.npz`` is
made and the findings: results/realdata_fresh15.md.
``--fresh16-records DIR`` (``FRESH16``, results/realdata_fresh16_table[_<split>].md): the
sixteenth sweep's record (an elbow driven by two pneumatic muscles, validated on a second
run); source, SHA-256, how the ``.npz`` is made and the findings: results/realdata_fresh16.md.
``--fresh17-records DIR`` (``FRESH17``, results/realdata_fresh17_table[_<split>].md): the
seventeenth sweep's records (a RoboCup robot's four wheel motors, a human ankle's stiffness, a
3D-printer hot-end), each validated on a second run; sources, SHA-256, how each ``.npz`` is
made and the findings: results/realdata_fresh17.md.
``--fresh18-records DIR`` (``FRESH18``, results/realdata_fresh18_table[_<split>].md): the
eighteenth sweep's records (a robot joint actuator on a dynamometer, a DC motor with a
tachogenerator, a cantilever on a shaker), each validated on a second run; sources, SHA-256,
how each ``.npz`` is made and the findings: results/realdata_fresh18.md.
``--fresh19-records DIR`` (``FRESH19``, results/realdata_fresh19_table[_<split>].md): the
nineteenth sweep's records (a human operator in a tracking loop, waves in a towing basin, a
DC plasma reactor), each validated on a second run; sources, SHA-256, how each ``.npz`` is
made and the findings: results/realdata_fresh19.md.
``--fresh20-records DIR`` (``FRESH20``, results/realdata_fresh20_table[_<split>].md): the
twentieth sweep's records (an unloaded instrumented treadmill, two carts coupled by a
spring), each validated on a second run; sources, SHA-256, how each ``.npz`` is made and the
findings: results/realdata_fresh20.md.
``--fresh21-records DIR`` (``FRESH21``, results/realdata_fresh21_table[_<split>].md): the
twenty-first sweep's records (an air pump pressurising a leaky vessel, one run split 2/3 /
1/3; a cyclist's heart rate against an ergometer's power, validated on a second ride);
sources, SHA-256, how each ``.npz`` is made and the findings: results/realdata_fresh21.md.
``--fresh22-records DIR`` (``FRESH22``, results/realdata_fresh22_table[_<split>].md): the
twenty-second sweep's records (a small thermal plant and a DC motor run over the internet,
each one run split 2/3 / 1/3; a heat pump in climate chambers, validated on another city's
day); sources, SHA-256, how each ``.npz`` is made and the findings: results/realdata_fresh22.md.
``--fresh23-records DIR`` (``FRESH23``, results/realdata_fresh23_table[_<split>].md): the
twenty-third sweep's records (a DC servomotor, a car's throttle valve, a propeller-driven
arm, each validated on a second run); sources, SHA-256, how each ``.npz`` is made and the
findings: results/realdata_fresh23.md.
``--fresh24-records DIR`` (``FRESH24``, results/realdata_fresh24_table[_<split>].md): the
twenty-fourth sweep's records (a flexible plate with a sloshing tank, a hovercraft's yaw,
each validated on a second run); sources, SHA-256, how each ``.npz`` is made and the
findings: results/realdata_fresh24.md.
``--fresh25-records DIR`` (``FRESH25``, results/realdata_fresh25_table[_<split>].md): the
twenty-fifth sweep's records (a double pendulum driven at both joints: a closed-loop
tracking run, an open-loop run of sine torques validated on a second run); sources, SHA-256,
how each ``.npz`` is made and the findings: results/realdata_fresh25.md.
``--fresh26-records DIR`` (``FRESH26``, results/realdata_fresh26_table[_<split>].md): the
twenty-sixth sweep's records (airborne wind energy: a soft kite's steering and a tethered
aircraft's control surfaces, both under their autopilots); sources, SHA-256, how each
``.npz`` is made and the findings: results/realdata_fresh26.md.
``--fresh27-records DIR`` (``FRESH27``, results/realdata_fresh27_table[_<split>].md): the
twenty-seventh sweep's record (a 7-joint robot arm's torques -> joint positions under its
joint controller); sources, SHA-256, how the ``.npz`` is made and the findings:
results/realdata_fresh27.md.
``--fresh28-records DIR`` (``FRESH28``, results/realdata_fresh28_table[_<split>].md): the
twenty-eighth sweep's records (a race car's camber actuator under its position servo, a
refinery's sulfur recovery unit, a plate heat exchanger, a greenhouse, a pH flask under its
controller, an active suspension rig); sources, SHA-256, how each ``.npz`` is made and the
findings: results/realdata_fresh28.md.
``--fresh29-records DIR`` (``FRESH29``, results/realdata_fresh29_table[_<split>].md): the
twenty-ninth sweep's records (a catchment, a micro gas turbine, a wastewater plant's
aeration, an MR damper, a walking robot's leg, a Li-ion cell, a Peltier cell, a pump, a
research jet's pitch, an office's CO2, an anaesthetised patient); sources, SHA-256, how each
``.npz`` is made and the findings: results/realdata_fresh29.md.
``--fresh30-records DIR`` (``FRESH30``, results/realdata_fresh30_table[_<split>].md): the
thirtieth sweep's records (a camera gimbal's brushless motor, a district heating network, a
brine-to-water heat pump on a bench, a pot of water under a PI loop, a person with type 1
diabetes, an aquifer's well, a reaction-wheel pendulum, a gas-fired coffee roaster); sources,
SHA-256, how each ``.npz`` is made and the findings: results/realdata_fresh30.md.
``--fresh31-records DIR`` (``FRESH31``, results/realdata_fresh31_table[_<split>].md): the
thirty-first sweep's records (a BMW i3's cabin heating, electric drive and traction battery,
a microgrid's battery bank, a mock circulatory loop, a ventilated patient, a fed-batch
fermenter, a servo swinging a pendulum, a fatigue-test rig, a heated incubator); sources,
SHA-256, how each ``.npz`` is made and the findings: results/realdata_fresh31.md.

Score: the simulation fit on the validation part, NRMSE %, ``100 (1 - |y - yhat| / |y -
mean(y)|)`` averaged over outputs, with the initial state fitted by least squares on the
validation data (as MATLAB's ``compare``), computed by :func:`sysid.compare` for every tool
(each model is handed over as ``A, B, C, D``). Stability: the largest pole modulus.

Tools. ``sysid.identify`` gets the raw records (it removes and records offsets itself); every
other tool gets the records with the estimation means removed (the same means from the
validation part), as a user would after sysid's offset warning.

- ``identify``: ``sysid.identify(est)`` with no settings.
- ``ssest``: ``sysid.ssest(est, order="auto")``; ``n4sid``, ``moesp``, ``cva``,
  ``ssregest``: at their defaults (``order="auto"``, default horizon).
- ``sippy``, ``nfoursid``: the peers (benches/.venv-peers, see benches/run.py), each at its
  best settings from a grid of orders (1-10, 12, 16, 20) and horizons (10, 20) chosen on the
  estimation data only: fitted on its first 2/3, scored by simulation fit on its last 1/3,
  the winner re-fitted on the whole estimation part. SIPPY: N4SID; nfoursid: its N4SID.
- ``numpy-pomoesp``: a plain PO-MOESP written here in NumPy (LQ of the Hankel matrices,
  SVD of the projection, ``A, C`` from the shift, ``B, D, x0`` by least squares), its order
  chosen the same way on the estimation data.
- ``scipy-ls``: that model refined by ``scipy.optimize.least_squares`` on the simulation error
  of the estimation data (all entries of ``A, B, C, D, x0``; finite-difference Jacobian).
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import time
import warnings
from pathlib import Path

import numpy as np

# the record tables read from ``DIR/<name>.npz``
from realdata_records import (  # noqa: F401
    FRESH,
    FRESH2,
    FRESH3,
    FRESH4,
    FRESH5,
    FRESH6,
    FRESH7,
    FRESH8,
    FRESH9,
    FRESH10,
    FRESH11,
    FRESH12,
    FRESH13,
    FRESH14,
    FRESH15,
    FRESH16,
    FRESH17,
    FRESH18,
    FRESH19,
    FRESH20,
    FRESH21,
    FRESH22,
    FRESH23,
    FRESH24,
    FRESH25,
    FRESH26,
    FRESH27,
    FRESH28,
    FRESH29,
    FRESH30,
    FRESH31,
    MORE,
    SWEEPS,
)

HERE = Path(__file__).resolve().parent
SHARED = Path("/work/shared/data")
ORDERS = (1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 12, 16, 20)
HORIZONS = (10, 20)


# -- records ------------------------------------------------------------------------------
SPLITS = ("default", "reversed", "swap")
SPLIT = "default"  # set by --split


def _split(u, y, n_est: int, split: str):
    """The estimation and validation parts of one record under a split (docstring)."""
    N = u.shape[0]
    if split == "default":
        e, v = slice(0, n_est), slice(n_est, N)
    elif split == "reversed":  # estimate on the last n_est samples, validate on the first
        e, v = slice(N - n_est, N), slice(0, N - n_est)
    elif split == "swap":  # estimate on the default validation part, validate on the rest
        e, v = slice(n_est, N), slice(0, n_est)
    else:
        raise ValueError(f"unknown split {split!r}; choose one of {SPLITS}")
    return (u[e], y[e]), (u[v], y[v])


def _daisy(name: str, ins: list[int], outs: list[int], n_est: int | None = None):
    d = np.loadtxt(SHARED / "daisy" / f"{name}.dat")
    n_est = n_est if n_est is not None else (2 * d.shape[0]) // 3
    return _split(d[:, ins], d[:, outs], n_est, SPLIT)


def _f16(level: str):
    """The F-16 levels keep their split under every --split (separate validation file)."""
    def read(f: str) -> np.ndarray:
        return np.genfromtxt(SHARED / "f16" / f, delimiter=",", skip_header=1)[:, :5]
    est = read(f"F16Data_FullMSine_{level}.csv")[8192:3 * 8192]
    val = read("F16Data_FullMSine_Level2_Validation.csv")[8192:2 * 8192]
    return (est[:, [0]], est[:, 2:5]), (val[:, [0]], val[:, 2:5])


RECORDS = {
    "dryer": lambda: _daisy("dryer", [0], [1], 500),
    "robot_arm": lambda: _daisy("robot_arm", [0], [1], 800),
    "flutter": lambda: _daisy("flutter", [0], [1]),
    "thermic_res_wall": lambda: _daisy("thermic_res_wall", [0, 1], [2], 1200),
    "winding": lambda: _daisy("winding", [0, 1, 2, 3, 4], [5, 6]),
    "cstr": lambda: _daisy("cstr", [1], [2, 3]),
    "ballbeam": lambda: _daisy("ballbeam", [0], [1]),
    "destill": lambda: _daisy("destill", [1, 2, 3, 4, 5], [21, 22, 23]),
    "ph": lambda: _daisy("pHdata", [1, 2], [3]),
    "f16_level1": lambda: _f16("Level1"),
    "f16_level3": lambda: _f16("Level3"),
}

#: DaISy records the project does not ship, read from a directory holding the collection's
#: files as distributed (``--unshipped DIR``): a check on records no choice was made on. The
#: first 2/3 estimate, the last 1/3 validate (every ``--split`` applies); columns: (file,
#: inputs, outputs) of the collection's descriptions (a leading time column is skipped)
UNSHIPPED = {
    "exchanger": ("exchanger", [1], [2]),  # steam heat exchanger: flow -> temperature
    "heating_system": ("heating_system", [1], [2]),  # heating system: voltage -> temperature
    "glassfurnace": ("glassfurnace", [1, 2, 3], [4, 5, 6, 7, 8, 9]),  # 3 heaters, 6 sensors
    "evaporator": ("evaporator", [0, 1, 2], [3, 4, 5]),  # four-stage evaporator
    "cd_player": ("CD_player_arm", [0, 1], [2, 3]),  # CD player arm (two forces, tracking)
    "dryer2": ("dryer2", [1, 2, 3], [4, 5, 6]),  # industrial dryer
    "steamgen": ("steamgen", [1, 2, 3, 4], [5, 6, 7, 8]),  # steam generator
    "powerplant": ("powerplant", [1, 2, 3, 4, 5], [6, 7, 8]),  # power plant (references left out)
}


def _more(folder: Path, name: str, table: dict | None = None):
    est, val = (MORE if table is None else table)[name]

    def read(f: str):
        z = np.load(folder / f"{f}.npz")
        return np.asarray(z["u"], float), np.asarray(z["y"], float)
    u, y = read(est)
    if val is not None:
        return (u, y), read(val)
    return _split(u, y, (2 * u.shape[0]) // 3, SPLIT)


#: the nonlinear benchmark records of ``--nonlinear-records`` and the test record each is
#: validated on (the files and splits of ``benches/nonlinear_unshipped.py``)
NONLINEAR_TESTS = {"tanks": "validation", "emps": "pulses", "silverbox": "multisine test",
                   "wh2009": "test"}


def _nonlinear(folder: str, name: str):
    """(estimation, validation) of a nonlinear benchmark record, training cut to 20 000."""
    import nonlinear_unshipped as nu

    nu.DIR, nu.MAX_TRAIN = folder, 20000
    train, test, _, _ = nu.LOADERS[name]()
    return train.experiments[0], test[NONLINEAR_TESTS[name]]


def _unshipped(folder: Path, name: str):
    f, ins, outs = UNSHIPPED[name]
    d = np.loadtxt(folder / f"{f}.dat")
    return _split(d[:, ins], d[:, outs], (2 * d.shape[0]) // 3, SPLIT)


# -- plain NumPy / SciPy reference (also run by the peers' worker: NumPy only) -------------
def simulate(A, B, C, D, u, x0=None):
    """x(t+1) = A x + B u, y = C x + D u: the modes of A filtered by scipy.signal.lfilter."""
    x0 = np.zeros(A.shape[0]) if x0 is None else np.asarray(x0, float)
    with np.errstate(all="ignore"):
        return modal_sim(A, B, C, D, x0, u)


def free_response(A, C, N):
    """The (N l) x n matrix of C A^t, t = 0..N-1 (from the eigen-decomposition of A)."""
    lam, V = np.linalg.eig(A)
    with np.errstate(all="ignore"):
        P = lam[None, :] ** np.arange(N)[:, None]  # N x n
        O = np.real(np.einsum("ln,tn,nk->tlk", C @ V, P, np.linalg.inv(V)))
    return O.reshape(N * C.shape[0], A.shape[0])


def sim_fit(A, B, C, D, u, y):
    """Simulation fit (NRMSE %, mean over outputs) with x0 by least squares."""
    ys = simulate(A, B, C, D, u)
    if not np.all(np.isfinite(ys)):
        return -np.inf
    O = free_response(A, C, u.shape[0])
    r = (y - ys).ravel()
    if np.all(np.isfinite(O)):
        x0 = np.linalg.lstsq(O, r, rcond=None)[0]
        ys = ys + (O @ x0).reshape(y.shape)
    dev = np.linalg.norm(y - y.mean(0), axis=0)
    return float(np.mean(100 * (1 - np.linalg.norm(y - ys, axis=0) / dev)))


def hankel(x, i, j):
    """Block Hankel matrix with i block rows and j columns of a (samples, channels) array."""
    return np.vstack([x[k:k + j].T for k in range(i)])


def po_moesp_ac(u, y, n_max, i):
    """PO-MOESP: the singular vectors of the projection; returns f(n) -> (A, C)."""
    m, l = u.shape[1], y.shape[1]
    j = u.shape[0] - 2 * i + 1
    Up, Uf = hankel(u, i, j), hankel(u[i:], i, j)
    Yp, Yf = hankel(y, i, j), hankel(y[i:], i, j)
    Z = np.vstack([Uf, Up, Yp, Yf])
    R = np.linalg.qr(Z.T, mode="r").T  # LQ: Z = R Q^T
    a, b = m * i, 2 * m * i + l * i
    R32 = R[b:, a:b]
    U, s, _ = np.linalg.svd(R32, full_matrices=False)

    def ac(n):
        Ob = U[:, :n] * np.sqrt(s[:n])
        C = Ob[:l]
        A = np.linalg.lstsq(Ob[:-l], Ob[l:], rcond=None)[0]
        return A, C
    return ac


def bd_x0(A, C, u, y):
    """B, D, x0 by linear least squares on the output equation."""
    N, m = u.shape
    n, l = A.shape[0], C.shape[0]
    cols = [free_response(A, C, N)]
    from scipy.signal import lfilter

    lam, V = np.linalg.eig(A)
    CV, Vi = C @ V, np.linalg.inv(V)
    for jj in range(m):
        # states driven by input jj through each unit column of B: x_k = V z, z filtered
        Z = np.stack([lfilter([0.0, 1.0], [1.0, -lam[q]], u[:, jj]) for q in range(n)], 1)
        for k in range(n):
            cols.append(np.real((Z * Vi[:, k]) @ CV.T).reshape(-1, 1))
    for r in range(l):
        for jj in range(m):
            col = np.zeros((N, l))
            col[:, r] = u[:, jj]
            cols.append(col.reshape(-1, 1))
    theta = np.linalg.lstsq(np.hstack(cols), y.ravel(), rcond=None)[0]
    x0, b = theta[:n], theta[n:n + n * m]
    B = b.reshape(m, n).T
    D = theta[n + n * m:].reshape(l, m)
    return B, D, x0


_AC_CACHE: dict = {}


def po_moesp(u, y, n, i):
    key = (u.shape, float(u.sum()), float(y.sum()), i)  # one SVD per record and horizon
    if key not in _AC_CACHE:
        _AC_CACHE.clear()
        _AC_CACHE[key] = po_moesp_ac(u, y, n, i)
    A, C = _AC_CACHE[key](n)
    B, D, _ = bd_x0(A, C, u, y)
    return A, B, C, D


def grid_choice(fit_fn, u, y, orders, horizons):
    """The (order, horizon) with the best simulation fit on the last third of the estimation
    data, fitted on its first two thirds."""
    k = (2 * u.shape[0]) // 3
    best = (-np.inf, None)
    for i in horizons:
        for n in orders:
            if n > i * y.shape[1] or k < 2 * i * (u.shape[1] + y.shape[1]) + 10:
                continue
            try:
                A, B, C, D = fit_fn(u[:k], y[:k], n, i)
                f = sim_fit(A, B, C, D, u[k:], y[k:])
            except Exception:  # noqa: BLE001 - a failed fit is not a candidate
                continue
            if np.isfinite(f) and f > best[0]:
                best = (f, (n, i))
    return best[1]


def numpy_pomoesp(u, y):
    choice = grid_choice(po_moesp, u, y, ORDERS, HORIZONS)
    if choice is None:
        raise RuntimeError("no order and horizon of the grid fits this record (too short)")
    n, i = choice
    A, B, C, D = po_moesp(u, y, n, i)
    return (A, B, C, D), {"order": n, "horizon": i}


def modal_sim(A, B, C, D, x0, u):
    """A faster simulation for the refinement: decoupled complex modes filtered by lfilter."""
    from scipy.signal import lfilter

    lam, V = np.linalg.eig(A)
    Vi = np.linalg.inv(V)
    Bu = u @ (Vi @ B).T
    z = np.empty((u.shape[0], A.shape[0]), complex)
    z0 = Vi @ x0
    for k in range(A.shape[0]):
        z[:, k] = lfilter([0.0, 1.0], [1.0, -lam[k]], Bu[:, k])
        z[:, k] += z0[k] * lam[k] ** np.arange(u.shape[0])
    return np.real(z @ (C @ V).T) + u @ D.T


def scipy_refine(u, y, start):
    from scipy.optimize import least_squares

    A, B, C, D = start
    n, m, l = A.shape[0], B.shape[1], C.shape[0]
    _, _, x0 = bd_x0(A, C, u, y)
    sizes = [n * n, n * m, l * n, l * m, n]

    def unpack(p):
        o = np.cumsum([0] + sizes)
        return (p[o[0]:o[1]].reshape(n, n), p[o[1]:o[2]].reshape(n, m),
                p[o[2]:o[3]].reshape(l, n), p[o[3]:o[4]].reshape(l, m), p[o[4]:o[5]])

    def res(p):
        a, b, c, d, x = unpack(p)
        with np.errstate(all="ignore"):
            e = (modal_sim(a, b, c, d, x, u) - y).ravel()
        return np.where(np.isfinite(e), e, 1e10)

    p0 = np.concatenate([A.ravel(), B.ravel(), C.ravel(), D.ravel(), x0])
    r = least_squares(res, p0, max_nfev=50, x_scale="jac")
    a, b, c, d, _ = unpack(r.x)
    return (a, b, c, d), {"nfev": int(r.nfev), "status": int(r.status)}


# -- peers (run under benches/.venv-peers by `--worker`) ------------------------------------
def sippy_fit(u, y, n, i):
    try:
        from sippy import system_identification
    except ImportError:  # sippy-unipi >= 1.0 installs the package as sippy_unipi
        from sippy_unipi import system_identification

    sys_id = system_identification(y.T, u.T, "N4SID", SS_fixed_order=n, SS_f=i, SS_p=i,
                                   SS_D_required=True)
    return (np.atleast_2d(sys_id.A), np.atleast_2d(sys_id.B), np.atleast_2d(sys_id.C),
            np.atleast_2d(sys_id.D))


def nfoursid_fit(u, y, n, i):
    from worker import run_nfoursid  # the scaling benchmark's call of nfoursid

    return run_nfoursid(u, y, i, n)[0]


def worker(tool: str, path: str) -> None:
    z = np.load(path)
    u, y = z["u"], z["y"]
    fn = {"sippy": sippy_fit, "nfoursid": nfoursid_fit}[tool]
    t = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        choice = grid_choice(fn, u, y, ORDERS, HORIZONS)
        if choice is None:
            raise RuntimeError("no setting of the grid gave a usable model")
        A, B, C, D = fn(u, y, *choice)
    print(json.dumps({"A": np.asarray(A).tolist(), "B": np.asarray(B).tolist(),
                      "C": np.asarray(C).tolist(), "D": np.asarray(D).tolist(),
                      "order": choice[0], "horizon": choice[1],
                      "seconds": time.perf_counter() - t}))


def run_peer(tool: str, u, y, tmp: Path, timeout: float = 900.0):
    py = HERE / ".venv-peers" / "bin" / "python"
    if not py.exists():
        raise RuntimeError("benches/.venv-peers missing (python benches/run.py --quick makes it)")
    np.savez(tmp, u=u, y=y)
    r = subprocess.run([str(py), __file__, "--worker", tool, str(tmp)], capture_output=True,
                       text=True, timeout=timeout)
    lines = [ln for ln in r.stdout.splitlines() if ln.startswith("{")]
    if not lines:
        raise RuntimeError((r.stderr.strip().splitlines() or ["no output"])[-1][:200])
    d = json.loads(lines[-1])
    mats = tuple(np.atleast_2d(np.asarray(d[k], float)) for k in "ABCD")
    return mats, {"order": d["order"], "horizon": d["horizon"], "seconds": d["seconds"]}


# -- sysid ------------------------------------------------------------------------------------
def _sysid_tools():
    import sysid

    def sub(name):
        return lambda est: getattr(sysid, name)(est)

    def ssest(est):
        try:
            return sysid.ssest(est, order="auto")
        except Exception:  # noqa: BLE001 - before order="auto" existed: the subspace choice
            return sysid.ssest(est, order=sysid.SubspaceEstimator(est).auto_order)

    tools = {"ssest": ssest, "n4sid": sub("n4sid"), "moesp": sub("moesp"), "cva": sub("cva")}
    if hasattr(sysid, "ssregest"):
        tools["ssregest"] = sub("ssregest")
    return tools


def score(mats, val, dt):
    import sysid

    A, B, C, D = (np.atleast_2d(np.asarray(x, float)) for x in mats)
    model = sysid.StateSpaceModel(A, B, C, D, dt=dt)
    rho = float(np.max(np.abs(np.linalg.eigvals(A)))) if A.size else 0.0
    try:
        with warnings.catch_warnings(), np.errstate(all="ignore"):
            warnings.simplefilter("ignore")
            f = float(sysid.compare(model, val).mean_fit)
    except Exception:  # noqa: BLE001 - a diverging model scores -inf
        f = -np.inf
    return (f if np.isfinite(f) else -np.inf), rho, A.shape[0]


SYSID_TOOLS = ("identify", "ssest", "n4sid", "moesp", "cva", "ssregest")


def run_record(name: str, peers: bool, tmpdir: Path, tools: set[str] | None = None,
               reuse: dict | None = None) -> list[dict]:
    import sysid

    (ue, ye), (uv, yv) = RECORDS[name]()
    mu, my = ue.mean(0), ye.mean(0)
    est = sysid.IOData(u=ue - mu, y=ye - my)
    val = sysid.IOData(u=uv - mu, y=yv - my)
    rows = []

    def add(tool, fn):
        # a tool left out of --tools is taken from the --reuse files when they have it; a
        # reference or peer tool (independent of sysid's code) is taken from them always
        left_out = tools is not None and tool not in tools
        if reuse and (name, tool) in reuse and (left_out or tool not in SYSID_TOOLS):
            rows.append(dict(reuse[(name, tool)], reused=True))
            print(json.dumps(rows[-1]), flush=True)
            return
        if left_out:
            return
        t = time.perf_counter()
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                mats, extra = fn()
            secs = extra.pop("seconds", time.perf_counter() - t)
            f, rho, n = score(mats, val, 1.0)
            f = extra.pop("fit_raw", f)
            row = {"record": name, "tool": tool, "fit": f, "max_pole": rho, "order": n,
                   "seconds": secs, "split": SPLIT, **extra}
        except Exception as e:  # noqa: BLE001 - reported, not raised
            row = {"record": name, "tool": tool, "fit": -np.inf, "max_pole": np.nan,
                   "order": None, "seconds": time.perf_counter() - t, "split": SPLIT,
                   "error": f"{type(e).__name__}: {e}"[:160]}
        rows.append(row)
        print(json.dumps(row), flush=True)

    if hasattr(sysid, "identify"):
        def ident():
            cpu = time.process_time()
            res = sysid.identify(sysid.IOData(u=ue, y=ye), progress=False)
            cpu = time.process_time() - cpu
            m = res.model.statespace
            # the fit on the raw validation data (offsets removed as the model records them;
            # NRMSE does not change with them): scored like every other tool, from A, B, C, D
            val_id = res.model.remove_offsets((uv, yv))
            f, rho, n = score((m.A, m.B, m.C, m.D), val_id, 1.0)
            return (m.A, m.B, m.C, m.D), {"choice": res.choice, "fit_raw": f,
                                          "seconds": res.seconds, "cpu_seconds": cpu,
                                          "out_of_time": res.out_of_time}
        add("identify", ident)
    for tool, fn in _sysid_tools().items():
        def f(fn=fn):
            m = fn(est)
            return (m.A, m.B, m.C, m.D), {}
        add(tool, f)
    add("numpy-pomoesp", lambda: numpy_pomoesp(est.u, est.y))
    if True:
        def refine():
            mats, _ = numpy_pomoesp(est.u, est.y)
            return scipy_refine(est.u, est.y, mats)
        add("scipy-ls", refine)
    if peers:
        for tool in ("sippy", "nfoursid"):
            add(tool, lambda tool=tool: run_peer(tool, est.u, est.y, tmpdir / f"{name}.npz"))
    return rows


def _cell(r: dict) -> str:
    if r.get("error"):
        return "failed"
    f = r["fit"]
    fs = "-inf" if not np.isfinite(f) else ("< -999" if f < -999 else f"{f:.1f}")
    flag = "" if r["max_pole"] < 1 else " (unstable)"
    return f"{fs} (n={r['order']}){flag}"


def goal_met(me: dict, others: list[dict]) -> str:
    """The issue's goal for identify's row ``me`` against the other tools' rows of the same
    record: stable and within 0.5 points of the best other, wherever any other reaches a
    positive fit ("yes"); or so against the stable others ("stable others: yes"); else "no"."""
    best = max(r["fit"] for r in others)
    stable = [r["fit"] for r in others if r["max_pole"] < 1]
    best_s = max(stable) if stable else -np.inf
    if best <= 0 or (me["max_pole"] < 1 and me["fit"] >= best - 0.5):
        return "yes"
    if best_s <= 0 or (me["max_pole"] < 1 and me["fit"] >= best_s - 0.5):
        return "stable others: yes"
    return "no"


def write_md(rows: list[dict], path: Path, argv: list[str]) -> None:
    tools = list(dict.fromkeys(r["tool"] for r in rows))
    records = list(dict.fromkeys(r["record"] for r in rows))
    by = {(r["record"], r["tool"]): r for r in rows}
    lines = [
        "# Real records: validation simulation fit (NRMSE %, mean over outputs)",
        "",
        f"Command: `.venv/bin/python benches/realdata.py {' '.join(argv)}`".replace("  ", " "),
        f"({time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}; splits and tools: see the "
        "docstring of benches/realdata.py). Cells: fit % (model order); `(unstable)` when "
        "a pole has modulus >= 1.",
        "",
        "| record | " + " | ".join(tools)
        + " | identify - best other | identify - best stable other | goal met |",
        "|---" * (len(tools) + 4) + "|",
    ]
    for rec in records:
        cells = [_cell(by[(rec, t)]) if (rec, t) in by else "" for t in tools]
        others = [by[(rec, t)] for t in tools if t != "identify" and (rec, t) in by]
        gap = gap_s = met = ""
        if (rec, "identify") in by and others:
            me = by[(rec, "identify")]
            best = max(r["fit"] for r in others)
            stable = [r["fit"] for r in others if r["max_pole"] < 1]
            best_s = max(stable) if stable else -np.inf

            def fmt(g):  # (-inf against -inf: no difference to state)
                return f"{g:+.1f}" if np.isfinite(g) else (
                    "-" if np.isnan(g) else "-inf" if g < 0 else "+inf")
            gap, gap_s = fmt(me["fit"] - best), fmt(me["fit"] - best_s)
            met = goal_met(me, others)
            if me.get("error"):  # no others' positive fit makes a refusal meet the goal
                met = "identify failed"
        lines.append(f"| {rec} | " + " | ".join(cells) + f" | {gap} | {gap_s} | {met} |")
    lines += ["", "Seconds per record and tool:", "",
              "| record | " + " | ".join(tools) + " |", "|---" * (len(tools) + 1) + "|"]
    for rec in records:
        lines.append(f"| {rec} | " + " | ".join(
            f"{by[(rec, t)]['seconds']:.1f}" if (rec, t) in by else "" for t in tools) + " |")
    ident = [r for r in rows if r["tool"] == "identify" and "cpu_seconds" in r]
    if ident:
        lines += ["", "`sysid.identify`: wall-clock and CPU seconds (the process's, all threads) "
                  "and the choice:", "", "| record | wall s | CPU s | time budget spent | choice |",
                  "|---|---|---|---|---|"]
        lines += [f"| {r['record']} | {r['seconds']:.1f} | {r['cpu_seconds']:.1f} | "
                  f"{'yes' if r.get('out_of_time') else 'no'} | {r.get('choice', '')} |"
                  for r in ident]
    if any(r.get("reused") for r in rows):
        lines += ["", "Rows marked reused were taken from an earlier run of the same script "
                  "(`--reuse`): the reference and peer tools (they do not depend on sysid's "
                  "code) and the sysid tools left out of `--tools`. Reused: "
                  + ", ".join(sorted({r["tool"] for r in rows if r.get("reused")})) + "."]
    errs = [r for r in rows if r.get("error")]
    if errs:
        lines += ["", "Failures:", ""] + [f"- {r['record']} / {r['tool']}: {r['error']}"
                                           for r in errs]
    path.write_text("\n".join(lines) + "\n")


def _use(args, names, load) -> None:
    """Run the records ``names`` (read by ``load(name)``) instead of the shipped ones, all of
    them unless ``--records`` picks some."""
    for name in names:
        RECORDS[name] = lambda name=name: load(name)
    if "--records" not in sys.argv:
        args.records = list(names)


def add_record_options(ap) -> None:
    """``--unshipped DIR`` and the sweeps' ``--<sweep>-records DIR`` (also for the scripts that
    scan the same records: offset_check.py, flat_scan.py)."""
    ap.add_argument("--unshipped", default=None, metavar="DIR",
                    help="run the DaISy records the project does not ship (UNSHIPPED), read "
                         "from DIR (the collection's .dat files), instead of the shipped ones")
    for sweep, (table, _) in SWEEPS.items():
        ap.add_argument(f"--{sweep}-records", default=None, metavar="DIR",
                        help=f"run the records of {table} (docstring), read from DIR/<name>.npz, "
                             "instead of the shipped ones")


def record_loaders(args) -> dict:
    """The shipped records' loaders and those of the folders ``args`` names
    (:func:`add_record_options`), by record name."""
    loads = dict(RECORDS)
    if args.unshipped:
        loads.update({n: (lambda n=n: _unshipped(Path(args.unshipped), n)) for n in UNSHIPPED})
    for sweep, (table, _) in SWEEPS.items():
        folder, names = getattr(args, f"{sweep}_records"), globals()[table]
        if folder:
            loads.update({n: (lambda n=n, f=folder, t=names: _more(Path(f), n, t))
                          for n in names})
    return loads


def main() -> None:
    if len(sys.argv) > 1 and sys.argv[1] == "--worker":
        worker(sys.argv[2], sys.argv[3])
        return
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--records", nargs="*", default=list(RECORDS))
    ap.add_argument("--no-peers", action="store_true")
    ap.add_argument("--split", choices=SPLITS, default="default",
                    help="estimation/validation split of the records (docstring); the F-16 "
                         "levels keep theirs")
    ap.add_argument("--out", default=None,
                    help="table .md (and .json beside it); default results/realdata.md, "
                         "results/realdata_<split>.md for another split")
    ap.add_argument("--tools", nargs="*", default=None, help="only these tools")
    ap.add_argument("--reuse", nargs="*", default=[],
                    help="results .json files whose reference and peer rows (not sysid's) "
                         "are taken instead of re-running them (marked in the table)")
    ap.add_argument("--table-from", default=None,
                    help="rewrite the table from a results .json (no fitting)")
    ap.add_argument("--nonlinear-records", default=None, metavar="DIR",
                    help="run the nonlinear benchmark records the project does not ship "
                         "(Silverbox, WH2009, cascaded tanks, EMPS; read from DIR as "
                         "benches/nonlinear_unshipped.py reads them, training cut to 20 000 "
                         "samples; their test records validate under every --split)")
    add_record_options(ap)
    args = ap.parse_args()
    global SPLIT
    SPLIT = args.split
    stem = "realdata"
    if args.nonlinear_records:
        stem = "realdata_nonlinear_records"
        _use(args, NONLINEAR_TESTS,
             lambda name: _nonlinear(args.nonlinear_records, name))
    if args.unshipped:
        stem = "realdata_unshipped"
        _use(args, UNSHIPPED, lambda name: _unshipped(Path(args.unshipped), name))
    for sweep, (table, sweep_stem) in SWEEPS.items():
        folder = getattr(args, f"{sweep}_records")
        if folder:
            stem, names = sweep_stem, globals()[table]
            _use(args, names, lambda name, f=folder, t=names: _more(Path(f), name, t))
    if args.out is None:
        tail = "" if args.split == "default" else f"_{args.split}"
        args.out = str(HERE / "results" / f"{stem}{tail}.md")
    if args.table_from:
        rows = json.loads(Path(args.table_from).read_text())
        for r in rows:
            r["fit"] = float(r["fit"])
            r["max_pole"] = float(r["max_pole"]) if r["max_pole"] is not None else np.nan
        write_md(rows, Path(args.out), [a for a in sys.argv[1:] if a != args.table_from
                                        and a != "--table-from"])
        print(Path(args.out).read_text())
        return
    tmpdir = HERE / ".data"
    tmpdir.mkdir(exist_ok=True)
    reuse = {}
    for f in args.reuse:
        for r in json.loads(Path(f).read_text()):
            # rows of another split are never reused (rows without one are the default's)
            if not r.get("error") and r.get("split", "default") == args.split:
                r["fit"] = float(r["fit"])
                r["max_pole"] = float(r["max_pole"])
                reuse[(r["record"], r["tool"])] = r
    rows = []
    for rec in args.records:
        rows += run_record(rec, not args.no_peers, tmpdir,
                           set(args.tools) if args.tools else None, reuse)
        write_md(rows, Path(args.out), sys.argv[1:])
        Path(args.out).with_suffix(".json").write_text(json.dumps(rows, indent=1, default=str))
    print(Path(args.out).read_text())


if __name__ == "__main__":
    main()
