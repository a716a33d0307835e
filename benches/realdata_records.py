"""The record tables of the sweeps ``benches/realdata.py`` reads from ``DIR/<name>.npz``
(``--more-records DIR``, ``--<sweep>-records DIR``): each name maps to its estimation file and,
if it has one, a separate validation file."""

#: records from outside DaISy the project does not ship (``--more-records DIR``): the files
#: ``DIR/<name>.npz`` hold ``u`` and ``y`` (samples x channels); a second name is a separate
#: validation record (kept under every split)
MORE = {
    "gas_furnace": ("gas_furnace_bj", None),  # gas rate -> CO2 (Box and Jenkins, series J)
    "buck": ("buck_converter_id", "buck_converter_valid"),  # duty cycle -> output voltage
    "dc_motor": ("dc_motor_generator_d500", None),  # motor voltage -> generator voltage
    "mr_damper": ("mr_damper_matlab", None),  # velocity -> force
    "ind_robot": ("industrial_robot_arm_matlab_est",  # motor torque -> motor speed
                  "industrial_robot_arm_matlab_val"),
    "flexible_structure": ("flexible_structure", None),  # 2 forces -> 28 accelerations
}


#: real records no run of the project had used before 2026-12-05 (``--fresh-records DIR``),
#: read as ``MORE``'s are (``DIR/<name>.npz``; how each file is made: the docstring)
FRESH = {
    "ced_prbs": ("ced_prbs", None),  # coupled electric drives, PRBS: drive voltage -> |speed|
    "ced_unif": ("ced_unif", None),  # the same, uniform-amplitude input
    "tclab_step": ("tclab_step", None),  # TCLab heater 1 step -> temperatures 1, 2
    "hsm150_step": ("hsm150_step", None),  # HSM150 motor torque steps -> speed
    "floatshield": ("floatshield_prbs", None),  # FloatShield fan PRBS -> ball height
    "motoshield": ("motoshield_aprbs", None),  # MotoShield voltage APRBS -> motor speed
    "magnetoshield": ("magneto_pid", None),  # MagnetoShield under PID: voltage -> position,
    # current (closed loop, an unstable plant)
}

#: real records of kinds no sweep had used (``--fresh2-records DIR``, second sweep of
#: 2026-12-05), read as ``FRESH``'s are; the irregular logs resampled onto their median
#: step by ``IOData.from_irregular`` (sources: results/realdata_fresh.md)
FRESH2 = {
    "tclab_pid2": ("tclab_pid2", None),  # TCLab, two heaters under PID: U1, U2 -> T1, T2
    "hydro_120": ("hydro_120", None),  # catchment 120, daily: rain, evaporation -> flow
    "mcar_sine": ("mcar_sine", None),  # balancing robot car, 2 ms: drive -> rate, angle
    "tailsitter": ("tailsitter_alt1", "tailsitter_alt2"),  # tail-sitter UAV, 100 Hz:
    # 4 actuator controls -> 3 body rates (flight 2 validates flight 1)
}

#: the third sweep's records (``--fresh3-records DIR``), read as ``FRESH``'s are (sources,
#: SHA-256 and how each ``.npz`` is made: results/realdata_fresh3.md)
FRESH3 = {
    "building_dtu": ("building_dtu", None),  # test building, 10 min: outdoor temperature,
    # heating power, solar radiation -> indoor temperature
    "pilot_level": ("pilot_level_est", "pilot_level_val"),  # level pilot plant, 10 s: pump
    # voltage -> water level (its test record validates)
    "mostar_step5": ("mostar_step5", None),  # hydro generator, AVR step test, 4.8 ms: field
    # voltage -> field current, terminal voltage, reactive power
    "attas_ailrud": ("attas_ailrud", None),  # ATTAS aircraft, 25 Hz: aileron, rudder -> roll
    # rate, yaw rate, lateral acceleration
}

#: the fourth sweep's records (``--fresh4-records DIR``), read as ``FRESH``'s are (sources:
#: results/realdata_fresh4.md)
FRESH4 = {
    "car_accel": ("car_accel", None),  # car, 20 Hz: acceleration command -> acceleration, speed
    "hydraulic_mts": ("hydraulic_mts", None),  # servo-hydraulic actuator, 1 kHz chirp:
    # commanded -> measured displacement
    "antx_pos": ("antx_pos", None),  # quadrotor on a 2-DoF bed, 4 ms: position set-point ->
    # position, pitch
}

#: the fifth sweep's records (``--fresh5-records DIR``), read as ``FRESH``'s are (sources:
#: results/realdata_fresh5.md)
FRESH5 = {
    "battery_hppc": ("battery_hppc", None),  # Nissan Leaf cell, HPPC at 25 degC, 2 s: current
    # -> terminal voltage
    "dyna_lateral": ("dyna_lateral1", "dyna_lateral2"),  # car, 10 ms: steering angle ->
    # lateral force (the second test validates the first)
    "ship_zigzag": ("ship_z20_05", "ship_z20_10p"),  # tanker model, zigzag 20/5 (relay on
    # the heading), 50 ms: rudder -> yaw rate, heading (the 20/10 zigzag validates)
}

#: the sixth sweep's records (``--fresh6-records DIR``), read as ``FRESH``'s are (sources:
#: results/realdata_fresh6.md)
FRESH6 = {
    "airduct90": ("airduct90_step", "airduct90_pid"),  # heated air duct, damper open (90 deg),
    # 10 ms: heater voltage -> air temperature; a 1 -> 5 V step test estimates, a PID run
    # (set-point step 30 -> 35 degC) validates
    "airduct45": ("airduct45_step", "airduct45_pid"),  # the same duct, damper at 45 deg
    "airduct90_ff": ("airduct90_ff", None),  # the duct at 90 deg under feedforward and PI
    # control (set-point step 30 -> 35 degC, closed loop): heater voltage -> temperature
    "aeroshield": ("aeroshield_id", "aeroshield_val"),  # propeller-driven pendulum, 10 ms: motor
    # voltage (APRBS) -> pendulum angle (the second test validates the first)
}

#: the seventh sweep's records (``--fresh7-records DIR``), read as ``FRESH``'s are (sources:
#: results/realdata_fresh7.md)
FRESH7 = {
    "fourtank_nmp": ("fourtank_nmp_dec", "fourtank_nmp_gm"),  # four-tank process, valves set
    # non-minimum-phase, 0.5 s, closed loop: pumps 1, 2 -> levels of tanks 1, 2; a run under
    # decentralised PI control estimates, a run under a Glover-McFarlane controller validates
    "fourtank_mp": ("fourtank_mp_dec", "fourtank_mp_gm"),  # the same rig, valves set
    # minimum-phase, the same two controllers
    "fourtank_manual": ("fourtank_manual", None),  # the minimum-phase rig under manual control
    # (an operator moving both pumps to hold the levels near 50 %)
}

#: the eighth sweep's records (``--fresh8-records DIR``), read as ``FRESH``'s are (sources:
#: results/realdata_fresh8.md)
FRESH8 = {
    "tower_hmd": ("tower_hmd_est", "tower_hmd_val"),  # five-storey steel test tower, white
    # noise into the hybrid mass damper on its roof, decimated to 25 Hz: actuator command ->
    # accelerations of floors 1-5 (a second white-noise run validates)
    "soft_actuator": ("soft_actuator_est", "soft_actuator_val"),  # soft pneumatic bending
    # actuator, 0.04 s: two pump voltages (on/off pulses) -> the two chamber pressures and the
    # bending angle (9 V pulses estimate, 7 V pulses validate)
    "optoshield": ("optoshield", None),  # OptoShield, 5 ms: LED power steps -> light on a
    # photoresistor
}

#: the ninth sweep's records (``--fresh9-records DIR``), read as ``FRESH``'s are (sources:
#: results/realdata_fresh9.md)
FRESH9 = {
    "polydome_summer": ("polydome_summer", None),  # a 600 m2 single-zone building's heat pump
    # (HVAC), 15 min, summer (cooling, no occupants): heat pump thermal power, outdoor
    # temperature, solar radiation -> four room temperatures
    "polydome_winter": ("polydome_winter", None),  # the same building in winter (heating)
    "crane_square": ("crane_square", None),  # gantry crane, decimated to 11.6 ms: trolley
    # motor voltage (a square wave, then rest) -> the load's swing (wire) angle
}

#: the tenth sweep's records (``--fresh10-records DIR``), read as ``FRESH``'s are (sources:
#: results/realdata_fresh10.md)
FRESH10 = {
    "rfl_square": ("rfl_square", None),  # Quanser rotary flexible link, 2 ms, under a servo
    # position controller (square-wave reference): motor voltage -> servo angle, link deflection
    "quad_roll_pid": ("quad_roll_pid", None),  # quadcopter on a one-axis roll rig under cascaded
    # PID, 100 ms telemetry: differential motor command -> roll angle, roll rate
    "wis_gate3_step": ("wis_gate3_step", None),  # irrigation-canal lab, decimated to 0.125 s:
    # a step on gate 3 (open loop) -> water levels of the pools upstream and downstream of it
    "wheel_loader": ("wheel_loader", None),  # wheel loader at work, 0.05 s: the operator's
    # throttle, lift and tilt levers -> engine speed, boom and bucket angular speeds
}

#: the eleventh sweep's records (``--fresh11-records DIR``), read as ``FRESH``'s are (sources:
#: results/realdata_fresh11.md)
FRESH11 = {
    "heli_pitch": ("heli_pitch", None),  # 2-DOF helicopter (twin rotor), 20 ms, open loop:
    # programmed pitch- and yaw-motor voltages -> pitch, yaw
    "heli_pitch_2runs": ("heli_pitch", "heli_pitch_b"),  # the same, a second run validates
    "heli_yaw": ("heli_yaw", None),  # the same rig, a pulse on the yaw motor -> yaw, pitch
}

#: the twelfth sweep's records (``--fresh12-records DIR``), each validated on a second run of
#: its rig (sources: results/realdata_fresh12.md)
FRESH12 = {
    "maglev_uaq": ("maglev_uaq", "maglev_uaq_val"),  # magnetic levitation under PID control,
    # 10 ms: coil voltage -> ball position, coil current (random reference steps; a session of
    # other steps validates)
    "brfd_damper": ("brfd_damper", "brfd_damper_val"),  # banded rotary friction damper, 1/1024
    # s: imposed displacement (an earthquake's) -> friction force (another earthquake validates)
    "em_actuator": ("em_actuator", "em_actuator_val"),  # electromagnetic haptic actuator,
    # 25 us: 0.5-1000 Hz chirp command -> coil current, vibrometer velocity (a repeat validates)
}

FRESH13 = {
    "qube_furuta": ("qube_furuta", "qube_furuta_val"),  # rotary inverted pendulum balanced
    # upright by a PD loop, 2 ms: the two references and a feedforward voltage -> arm and
    # pendulum angles (another run's seed validates)
    "fsm_piezo": ("fsm_piezo", "fsm_piezo_val"),  # piezo fine steering mirror, 3 x 3, 1/6400 s:
    # two periods of a random-phase multisine -> three displacements (another realisation)
    "voicecoil_chopper": ("voicecoil_chopper", "voicecoil_chopper_val"),  # loudspeaker driving
    # an optical chopper, 1 ms: a 1 Hz sine -> LVDT position (a run at another amplitude)
}

FRESH14 = {
    "slfr": ("slfr", "slfr_val"),  # single-link flexible robot under a lead compensator, 2 ms:
    # the motor command sent -> motor encoder, tip accelerometer (a second sweep validates)
    "vent": ("vent", None),  # ventilator on a test lung under PI pressure control, 10 ms:
    # inhale valve command -> patient pressure, two flow-sensor pressures
}

FRESH15 = {
    "shake1": ("shake1", "shake1_val"),  # a one-storey model on a small shake table, 120 Hz:
    # table acceleration (El Centro) -> top-floor acceleration (a second trial validates)
    "trms_pitch": ("trms_pitch", "trms_pitch_val"),  # a home-built twin rotor's pitch, 0.1 s:
    # a random binary offset on the main rotor's command -> pitch angle (another run)
    "engine": ("engine", "engine_val"),  # a gasoline engine on a test bench, 10 Hz: speed,
    # load, lambda, ignition angle -> particles, HC, NOx, two temperatures (the test run)
}

FRESH16 = {
    "pneumatic_arm": ("pneumatic_arm", "pneumatic_arm_val"),  # an elbow driven by two
    # antagonistic pneumatic muscles, open loop, 10 ms: muscle-1 pressure command -> angle
}

FRESH17 = {
    # a RoboCup small-size robot lifted off the floor, 10 ms: one PWM duty to its four wheel
    # motors -> the four wheel speeds (a second random-level run validates)
    "robocup_wheel_motors": ("robocup_wheel_motors", "robocup_wheel_motors_val"),
    # a human ankle under pseudo-random position perturbations, 1 ms: ankle angle -> ankle
    # torque (another trial validates)
    "ankle_stiffness": ("ankle_stiffness", "ankle_stiffness_val"),
    # a 3D-printer hot-end on a HeatShield board, 2 s: heater duty -> temperature (a
    # staircase of duties validates)
    "heatshield_hotend": ("heatshield_hotend", "heatshield_hotend_val"),
}

FRESH18 = {
    # a legged robot's joint actuator on a dynamometer, 5 ms (interpolated from an irregular
    # log): a random current command -> shaft speed, torque (another day's run validates)
    "actuator_dyno_ex8": ("actuator_dyno_ex8", "actuator_dyno_ex8_val"),
    # a DC motor driving a tachogenerator through a belt, 0.1 s: a PWM command of random
    # levels -> tacho voltage (a second run validates)
    "motor_tacho_belt": ("motor_tacho_belt", "motor_tacho_belt_val"),
    # a steel cantilever on an electromagnetic shaker, 1/3200 s: three tones of drive voltage
    # -> load-cell force, tip acceleration (a second test validates)
    "cantilever_beam_shaker": ("cantilever_beam_shaker", "cantilever_beam_shaker_val"),
}

FRESH19 = {
    # a human operator tracking a seven-sine reference with a slider on a simulated
    # second-order machine, 1/60 s: reference -> slider force, cursor position (closed
    # through the human; another trial, other phases, validates)
    "hitl_tracking": ("hitl_tracking", "hitl_tracking_val"),
    # irregular waves in a towing basin, 0.1 s: wavemaker flap angle -> wave elevation at
    # two probes 26 and 30 m down the basin (the same drive at half amplitude validates)
    "wave_flume_flap": ("wave_flume_flap", "wave_flume_flap_val"),
    # a DC glow-discharge plasma reactor, 20 us: a two-level current command -> the probe
    # voltages either side of the reactor, the discharge current (a second capture validates)
    "plasma_dc": ("plasma_dc", "plasma_dc_val"),
}

FRESH20 = {
    # an unloaded instrumented treadmill, 0.01 s: measured belt speed (a random profile
    # around 2 m/s) -> the force plates' pitch moment (another trial validates)
    "treadmill_pitch": ("treadmill_pitch", "treadmill_pitch_val"),
    # two carts coupled by a spring, 1 ms: a square wave of motor voltage -> both carts'
    # velocities (a run at three quarters of the amplitude validates)
    "mte360_twocart": ("mte360_twocart", "mte360_twocart_val"),
}

FRESH21 = {
    # an air pump pressurising a leaky vessel (AutomationShield PressureShield), 10 ms: pump
    # command of random levels -> pressure (one run: first 2/3 / last 1/3)
    "pressureshield": ("pressureshield", None),
    # a rider on a cycle ergometer, 1 s: power (a step test) -> heart rate (a video ride of
    # freely varying power six days later validates)
    "ergometer_hr": ("ergometer_hr", "ergometer_hr_val"),
}

FRESH22 = {
    # a small thermal plant run over the internet (UNThermal), 1 s: a PRBS on the heater ->
    # the temperature (one run: first 2/3 / last 1/3)
    "unthermal_prbs": ("unthermal_prbs", None),
    # a small DC motor on the same platform, 20 ms: a PRBS on the voltage -> the speed
    # (one run: first 2/3 / last 1/3)
    "undcmotor_prbs": ("undcmotor_prbs", None),
    # a two-stage heat pump in hardware-in-the-loop climate chambers (NIST), 60 s:
    # thermostat's stage command, outdoor and indoor air temperatures -> supply-air
    # temperature, outdoor-unit power (Tucson's day; Atlanta's validates)
    "ashp_hil_stage": ("ashp_hil_stage", "ashp_hil_stage_val"),
}

FRESH23 = {
    # a DC servomotor (UNDCMotor, the 22nd sweep's rig; two later runs), 20 ms: a PRBS on the
    # voltage -> the speed (the second run validates)
    "dcmotor_speed_prbs": ("dcmotor_speed_prbs", "dcmotor_speed_prbs_val"),
    # a car's electronic throttle valve on a bench, 1 ms: a chirp on the voltage -> the plate's
    # angle, the motor's current (a repeat validates)
    "throttle_valve_chirp": ("throttle_valve_chirp", "throttle_valve_chirp_val"),
    # a propeller-driven arm (VTOL), 10 ms: multi-level steps of the motor command -> the
    # arm's angle (a later run validates)
    "vtol_arm_angle_steps": ("vtol_arm_angle_steps", "vtol_arm_angle_steps_val"),
}

FRESH24 = {
    # a flexible plate with a water tank at its tip (sloshing), 1 ms: a chirp on two piezo
    # patches (one voltage) -> two tip accelerations (a repeat validates)
    "beam_tank_piezo_chirp": ("beam_tank_piezo_chirp", "beam_tank_piezo_chirp_val"),
    # a small hovercraft tracked by motion capture, 10 ms: two thrusters' on/off commands
    # (a PRBS) -> the yaw angle (another run validates)
    "hovercraft_yaw_prbs": ("hovercraft_yaw_prbs", "hovercraft_yaw_prbs_val"),
}

FRESH25 = {
    # a double pendulum (two torque-controlled joint motors), 1/300 s: the measured joint
    # torques -> the two joint angles while a PID tracks a 75 s trajectory (closed loop;
    # split 2/3 : 1/3)
    "double_pendulum_track": ("double_pendulum_track", None),
    # the same rig in open loop, 2 ms: a sine torque command on each joint -> the two angles
    # (a second run, the two frequencies swapped between the joints, validates)
    "double_pendulum_sine": ("double_pendulum_sine", "double_pendulum_sine_val"),
}

FRESH26 = {
    # a 25 m^2 soft kite flying pumping cycles under its autopilot (closed loop), 0.1 s: the
    # realised steering and depower -> the kite's yaw rate (the next cycle validates)
    "kite_steer_yawrate": ("kite_steer_yawrate", "kite_steer_yawrate_val"),
    # a tethered rigid-wing aircraft (Ampyx AP2) in one pumping cycle, 20 ms: aileron,
    # elevator and rudder demands of its flight computer -> roll, pitch and yaw rates
    # (closed loop; split 2/3 : 1/3)
    "ampyx_ap2_rates": ("ampyx_ap2_rates", None),
}

FRESH27 = {
    # a 7-joint robot arm (Franka Emika Panda) following an exciting Fourier-series trajectory
    # under its joint controller (closed loop), 1 ms: the seven joint torques -> the seven
    # joint positions (split 2/3 : 1/3)
    "franka_panda": ("franka_panda", None),
}

FRESH28 = {
    # a race car's camber/toe linear actuator under its drive's position controller, 10 ms:
    # target position -> measured position (a sine sweep; a square-wave run validates)
    "camber_lind": ("camber_lind", "camber_lind_val"),
    # a refinery's sulfur recovery unit, 1 min, operating records (closed loop): MEA gas and
    # air flows, secondary air, SWS gas and air flows -> H2S, SO2 in the tail gas (split
    # 2/3 : 1/3)
    "sru_sulfur": ("sru_sulfur", None),
    # a laboratory plate heat exchanger, 2 s: hot-water valve command -> outlet temperature
    # (random levels; a staircase run validates)
    "phe_valve": ("phe_valve", "phe_valve_val"),
    # a small research greenhouse, 5 min, under its fan, heater and light rules (closed
    # loop): lights, fan, heater (on-fractions), outside temperature and light -> inside
    # temperature and humidity (split 2/3 : 1/3)
    "greenhouse_mini": ("greenhouse_mini", None),
    # a stirred flask titrated by an acid pump under a pH controller (closed loop; the log
    # resampled onto 0.34 s): acid flow -> pH (split 2/3 : 1/3)
    "ph_flask_acid": ("ph_flask_acid", None),
    # a quarter-car active suspension rig (Quanser), 2 ms, open loop: road position, actuator
    # force (both chirps) -> tire and body plate positions (a second chirp run validates)
    "active_suspension": ("active_suspension_chirp", "active_suspension_chirp_val"),
}

FRESH29 = {
    # a catchment (Leaf River above Collins, Mississippi), daily: precipitation, potential
    # evapotranspiration -> streamflow (water years 1949-1968; 1969-1988 validate)
    "leaf_river": ("leaf_river", "leaf_river_val"),
    # a 3 kW micro gas turbine under its own power controller, 1 s: the set-point voltage's
    # levels -> electrical power (another experiment's levels validate)
    "micro_gas_turbine": ("micro_gas_turbine_power", "micro_gas_turbine_power_val"),
    # a municipal wastewater plant's aeration (Tilburg), 15 min, under its ammonium/oxygen
    # cascade (closed loop): influent flow, five air flows, temperature -> oxygen in three
    # tanks, nitrate, ammonium (split 2/3 : 1/3)
    "wwtp_aeration": ("wwtp_tilburg_aeration", None),
    # a magnetorheological damper on a hydraulic rig, 3 kHz, open loop: displacement, coil
    # voltage (random) -> force (another random run validates)
    "mr_damper_wn": ("mr_damper_whitenoise", "mr_damper_whitenoise_val"),
    # one leg of a compass-gait walking robot swinging from its hip motor, 5 ms, open loop:
    # motor command -> leg angle (the other leg's run of the same commands validates)
    "compass_gait_leg": ("compass_gait_leg_swing", "compass_gait_leg_swing_val"),
    # a Li-ion cell (Panasonic 18650PF) through drive cycles, 0.1 s: current -> terminal
    # voltage, case temperature (US06 estimates, LA92 validates)
    "li_ion_18650_drive": ("panasonic_18650pf_drive", "panasonic_18650pf_drive_val"),
    # a Peltier cell heated by pulses of an extruder heater, 0.25 s: heater on/off -> cell
    # voltage, hot- and cold-side temperatures (the last three pulses validate)
    "peltier_pulses": ("peltier_extruder_pulses", "peltier_extruder_pulses_val"),
    # a water pump in a flow loop (a course rig), 0.1 s, open loop: a two-level random
    # voltage -> flow (a run at another working point validates)
    "pump_flow_prbs": ("pump_flow_prbs", "pump_flow_prbs_val"),
    # a research jet's longitudinal motion in flight (Cessna Citation II), 0.1 s, flown by
    # hand: elevator -> pitch rate, angle of attack, pitch angle, airspeed (another flight's
    # manoeuvres validate)
    "citation_pitch": ("citation_elevator_pitch", "citation_elevator_pitch_val"),
    # an occupied office's air (a university building), 1 min: ventilation valve opening,
    # presence flag -> CO2 (the following week validates)
    "office_co2": ("office_co2_ventilation", "office_co2_ventilation_val"),
    # a patient under intravenous anaesthesia (VitalDB case 317), 10 s, the anaesthetist in
    # the loop: propofol, remifentanil infusion rates -> bispectral index (split 2/3 : 1/3)
    "propofol_bis": ("propofol_bis_vitaldb_all", None),
}

FRESH30 = {
    # a one-axis camera gimbal's brushless motor driven open loop (a lab rig), 5 ms: field
    # angle command (square wave) -> camera angle, gyro rate (a second run validates)
    "gimbal_bldc_steps": ("gimbal_bldc_steps", "gimbal_bldc_steps_val"),
    # a district heating network's branch (Pongau), 15 min, in operation: feed temperature,
    # three substation flows, outdoor temperature -> three substation temperatures (2/3 : 1/3)
    "dh_network_pongau": ("dh_network_pongau", None),
    # a brine-to-water heat pump on a test bench (RWTH EBC), 1 s: compressor and pump
    # statuses, water return and brine inlet temperatures -> water supply temperature,
    # electrical power, brine outlet temperature (2/3 : 1/3; the last third is the shutdown)
    "brine_hp_bench": ("brine_hp_bench", None),
    # a pot of water on an electric hot plate under PI control, 10 s: power -> water and
    # plate temperatures (a repeat run validates)
    "cooking_pot_pi": ("cooking_pot_pi", "cooking_pot_pi_val"),
    # one person with type 1 diabetes in free living, 5 min: insulin, carbohydrate ->
    # interstitial glucose (2/3 : 1/3)
    "t1d_glucose_insulin": ("t1d_glucose_insulin", None),
    # an alluvial aquifer's well (Gossau), daily: precipitation, evaporation -> groundwater
    # head (1998-2021 estimate, 1991-1996 validate)
    "gossau_groundwater": ("gossau_groundwater", "gossau_groundwater_val"),
    # a reaction-wheel pendulum hanging down (a student rig), 50 ms, open loop: motor command
    # (a chirp) -> pendulum angle, wheel speed (a sine run validates)
    "reaction_pendulum_chirp": ("reaction_pendulum_chirp", "reaction_pendulum_chirp_val"),
    # an empty gas-fired coffee roaster's drum, 1 s, stepped by hand: burner, air flow ->
    # exhaust and drum temperatures (2/3 : 1/3; the last part is the cool-down)
    "coffee_roaster_gas_air": ("coffee_roaster_gas_air", None),
}

FRESH31 = {
    # a BMW i3's cabin heating in winter driving (TU Munich data set), 0.1 s, closed loop
    # (automatic climate control): heater power, ambient temperature -> coolant temperature
    # at the heater core, cabin temperature (trip B03 estimates, trip B27 validates)
    "bmw_i3_cabin_heater": ("bmw_i3_cabin_heater", "bmw_i3_cabin_heater_val"),
    # the same car's electric drive, 0.1 s, driven in traffic: accelerator pedal -> motor
    # torque, longitudinal acceleration (trip B03 estimates, trip B27 validates)
    "bmw_i3_pedal_accel": ("bmw_i3_pedal_accel", "bmw_i3_pedal_accel_val"),
    # the same car's high-voltage battery in summer driving, 0.1 s: current -> voltage (trip
    # A12 estimates, trip A05 validates)
    "bmw_i3_hv_battery": ("bmw_i3_hv_battery", "bmw_i3_hv_battery_val"),
    # an off-grid microgrid's 48 V battery bank (NPS rooftop), 1 min, the inverter-charger
    # in the loop: current -> voltage (2/3 : 1/3)
    "spanagel_battery": ("spanagel_battery", None),
    # the FDA mock circulatory loop, 1 ms, beats at 75/min with ventilation-like stroke
    # modulation: aortic flow -> aortic and radial pressures (a second run validates)
    "mcl_aortic_flow_rr12": ("mcl_aortic_flow_rr12", "mcl_aortic_flow_rr12_val"),
    # a ventilated ICU patient (pressure-targeted PB-840), 20 ms, 1 000 breaths: airway
    # pressure -> flow (2/3 : 1/3; the patient's own effort unmeasured)
    "icu_vent_pb840": ("icu_vent_pb840", None),
    # a fed-batch fermentation of C. glutamicum, 1 min: glucose feed, stirrer, air feed ->
    # dissolved O2, off-gas CO2 and O2 (2/3 : 1/3; the stirrer in the DO loop)
    "cglut_fedbatch": ("cglut_fedbatch", None),
    # a Dynamixel XL330 servo swinging a pendulum under its own P loop, 5 ms: goal position ->
    # arm angle (a sine run estimates, a chirp run validates)
    "xl330_pendulum": ("xl330_pendulum", "xl330_pendulum_val"),
    # the NRC FASTER fatigue rig, 7.75 ms, force-controlled (closed loop): actuator command
    # -> force, beam displacement (the authors' halves)
    "faster_beam_force": ("faster_beam_force", "faster_beam_force_val"),
    # a heated incubator box (Aarhus digital-twin case), 3 s, random heater pulses, open
    # loop: heater on/off, room temperature -> two in-box temperatures (a second run
    # validates)
    "incubator_box": ("incubator_box", "incubator_box_val"),
}

#: the sweeps read from ``DIR/<name>.npz``: ``--<sweep>-records DIR`` runs a table's records
#: into ``results/<stem>[_<split>].md`` (the third sweep's tables beside its account,
#: results/realdata_fresh3.md)
SWEEPS = {"more": ("MORE", "realdata_more"), "fresh": ("FRESH", "realdata_fresh"),
          "fresh2": ("FRESH2", "realdata_fresh2"), "fresh3": ("FRESH3", "realdata_fresh3_table"),
          "fresh4": ("FRESH4", "realdata_fresh4_table"),
          "fresh5": ("FRESH5", "realdata_fresh5_table"),
          "fresh6": ("FRESH6", "realdata_fresh6_table"),
          "fresh7": ("FRESH7", "realdata_fresh7_table"),
          "fresh8": ("FRESH8", "realdata_fresh8_table"),
          "fresh9": ("FRESH9", "realdata_fresh9_table"),
          "fresh10": ("FRESH10", "realdata_fresh10_table"),
          "fresh11": ("FRESH11", "realdata_fresh11_table"),
          "fresh12": ("FRESH12", "realdata_fresh12_table"),
          "fresh13": ("FRESH13", "realdata_fresh13_table"),
          "fresh14": ("FRESH14", "realdata_fresh14_table"),
          "fresh15": ("FRESH15", "realdata_fresh15_table"),
          "fresh16": ("FRESH16", "realdata_fresh16_table"),
          "fresh17": ("FRESH17", "realdata_fresh17_table"),
          "fresh18": ("FRESH18", "realdata_fresh18_table"),
          "fresh19": ("FRESH19", "realdata_fresh19_table"),
          "fresh20": ("FRESH20", "realdata_fresh20_table"),
          "fresh21": ("FRESH21", "realdata_fresh21_table"),
          "fresh22": ("FRESH22", "realdata_fresh22_table"),
          "fresh23": ("FRESH23", "realdata_fresh23_table"),
          "fresh24": ("FRESH24", "realdata_fresh24_table"),
          "fresh25": ("FRESH25", "realdata_fresh25_table"),
          "fresh26": ("FRESH26", "realdata_fresh26_table"),
          "fresh27": ("FRESH27", "realdata_fresh27_table"),
          "fresh28": ("FRESH28", "realdata_fresh28_table"),
          "fresh29": ("FRESH29", "realdata_fresh29_table"),
          "fresh30": ("FRESH30", "realdata_fresh30_table"),
          "fresh31": ("FRESH31", "realdata_fresh31_table")}
