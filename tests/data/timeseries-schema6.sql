-- A real schema-6 database: 'dsfd run --config config/panels/suwon-south.yaml --dry-run --plant sim
-- --plant-fidelity lumped --cycles 3' of dsfd at commit 0efe0ad (before schema 7), dumped with
-- Python's sqlite3 iterdump; tests/storage/test_findings_migration.py rebuilds it.
BEGIN TRANSACTION;
CREATE TABLE comfort (
    run_id INTEGER NOT NULL REFERENCES runs(run_id),
    cycle INTEGER NOT NULL,
    time_s REAL NOT NULL,
    occupied INTEGER NOT NULL,
    occupancy_source TEXT NOT NULL,
    direct_sun_wm2 REAL,
    dgp REAL,
    supply_air_c REAL,
    asymmetry_k REAL,
    direct_sun_max_wm2 REAL,
    dgp_max REAL,
    supply_air_min_c REAL,
    asymmetry_max_k REAL,
    violations TEXT NOT NULL DEFAULT '[]',
    PRIMARY KEY (run_id, cycle)
);
INSERT INTO "comfort" VALUES(1,1,1640964780.0,0,'schedule',0.0,0.184,NULL,-1.73325649002549653232e+00,5.0,0.35,1.84451722585695776501e+01,10.0,'[]');
INSERT INTO "comfort" VALUES(1,2,1640964840.0,0,'schedule',0.0,0.184,NULL,-1.7501328536188225371e+00,5.0,0.35,1.84451722585695776501e+01,10.0,'[]');
INSERT INTO "comfort" VALUES(1,3,1640964900.0,0,'schedule',0.0,0.184,NULL,-1.56471207663958011835e+00,5.0,0.35,1.84451722585695776501e+01,10.0,'[]');
CREATE TABLE commands (
    command_id INTEGER PRIMARY KEY AUTOINCREMENT,
    requested_s REAL NOT NULL,
    requested_utc TEXT NOT NULL,
    source TEXT NOT NULL,
    requester TEXT NOT NULL,
    kind TEXT NOT NULL,
    args TEXT NOT NULL DEFAULT '{}',
    status TEXT NOT NULL DEFAULT 'pending',
    reason TEXT NOT NULL DEFAULT '',
    run_id INTEGER,
    cycle INTEGER,
    handled_utc TEXT
);
CREATE TABLE decisions (
    run_id INTEGER NOT NULL REFERENCES runs(run_id),
    cycle INTEGER NOT NULL,
    slot INTEGER NOT NULL,
    time_s REAL NOT NULL,
    time_utc TEXT NOT NULL,
    method TEXT NOT NULL,
    fallback_reason TEXT NOT NULL DEFAULT '',
    heating INTEGER,
    cost_j REAL,
    proposed_phi_deg REAL,
    proposed_afr INTEGER,
    proposed_or_pct REAL,
    phi_deg REAL NOT NULL,
    afr INTEGER NOT NULL,
    or_pct REAL NOT NULL,
    write_status TEXT NOT NULL,
    write_errors TEXT NOT NULL DEFAULT '[]',
    trace TEXT NOT NULL DEFAULT '[]',
    timings_ms TEXT NOT NULL DEFAULT '{}',
    cycle_ms REAL NOT NULL,
    skipped_slots INTEGER NOT NULL DEFAULT 0,
    hold_source TEXT,
    hold_expires_s REAL,
    hold_command_id INTEGER,
    run_elapsed_s REAL,
    objective_mode TEXT,
    mode_command_id INTEGER,
    occupancy_override TEXT,
    occupancy_until_s REAL,
    occupancy_command_id INTEGER,
    PRIMARY KEY (run_id, cycle)
);
INSERT INTO "decisions" VALUES(1,1,0,1640964780.0,'2021-12-31T15:33:00Z','mpc','',1,1.1719635238819610095e+05,0.0,5,100.0,0.0,5,100.0,'verified','[]','[{"stage":"decide:mpc","set":{"phi_deg":0.0,"afr":5,"or_pct":100.0},"why":"candidates: 11 louver positions x 6 damper sets (regimes [1, 3, 5, 6, 9, 10]), OR grid [0.0, 100.0] % | stage 1: screened 121 candidates at 300 s steps | stage 2: 13 at full resolution (12 finalists, OR brackets of 1 pairs), best louver +0 deg, regime 5, OR 100.0 %, J +32.55 Wh | stage 3: not needed (the best''s louver neighbours were evaluated)"},{"stage":"wind","set":{},"why":"wind 1.8 m/s below 15 m/s"},{"stage":"hold","set":{},"why":"no manual hold"},{"stage":"faults","set":{},"why":"no fault"},{"stage":"limits","set":{},"why":"louver -90..90 deg, dampers 0..100 %"},{"stage":"quantisation","set":{},"why":"louver onto the 18 deg motor grid, dampers onto 1 % steps"},{"stage":"rate","set":{},"why":"within rate limits"},{"stage":"regimes","set":{},"why":"regime 5 available"},{"stage":"occupancy","set":{"occupied":false,"source":"schedule"},"why":"unoccupied: no occupancy schedule"},{"stage":"comfort","set":{},"why":"unoccupied (no limit); direct sun 0 W/m2, DGPs 0.18, supply air none, asymmetry -1.7 K"}]','{"read":2.121,"quality":0.053,"estimate":1.286,"calibrate":0.017,"decide":23.119,"safety":0.114,"write":0.128,"predict":5.367,"comfort":1.165}',33.37,0,NULL,NULL,NULL,0.0,'auto',NULL,NULL,NULL,NULL);
INSERT INTO "decisions" VALUES(1,2,1,1640964840.0,'2021-12-31T15:34:00Z','mpc','',1,1.17590508001069480085e+05,0.0,5,100.0,0.0,5,100.0,'verified','[]','[{"stage":"decide:mpc","set":{"phi_deg":0.0,"afr":5,"or_pct":100.0},"why":"candidates: 11 louver positions x 6 damper sets (regimes [1, 3, 5, 6, 9, 10]), OR grid [0.0, 100.0] % | stage 1: screened 121 candidates at 300 s steps | stage 2: 13 at full resolution (12 finalists, OR brackets of 1 pairs), best louver +0 deg, regime 5, OR 100.0 %, J +32.66 Wh | stage 3: not needed (the best''s louver neighbours were evaluated)"},{"stage":"wind","set":{},"why":"wind 1.8 m/s below 15 m/s"},{"stage":"hold","set":{},"why":"no manual hold"},{"stage":"faults","set":{},"why":"no fault"},{"stage":"limits","set":{},"why":"louver -90..90 deg, dampers 0..100 %"},{"stage":"quantisation","set":{},"why":"louver onto the 18 deg motor grid, dampers onto 1 % steps"},{"stage":"rate","set":{},"why":"within rate limits"},{"stage":"regimes","set":{},"why":"regime 5 available"},{"stage":"occupancy","set":{"occupied":false,"source":"schedule"},"why":"unoccupied: no occupancy schedule"},{"stage":"comfort","set":{},"why":"unoccupied (no limit); direct sun 0 W/m2, DGPs 0.18, supply air none, asymmetry -1.8 K"}]','{"read":5.446,"quality":0.045,"estimate":3.389,"calibrate":0.019,"decide":22.317,"safety":0.128,"write":0.147,"predict":5.57,"comfort":0.67}',37.731,0,NULL,NULL,NULL,60.0,'auto',NULL,NULL,NULL,NULL);
INSERT INTO "decisions" VALUES(1,3,2,1640964900.0,'2021-12-31T15:35:00Z','mpc','',1,1.07682166172106255543e+05,0.0,5,100.0,0.0,5,100.0,'verified','[]','[{"stage":"decide:mpc","set":{"phi_deg":0.0,"afr":5,"or_pct":100.0},"why":"candidates: 11 louver positions x 6 damper sets (regimes [1, 3, 5, 6, 9, 10]), OR grid [0.0, 100.0] % | stage 1: screened 121 candidates at 300 s steps | stage 2: 13 at full resolution (12 finalists, OR brackets of 1 pairs), best louver +0 deg, regime 5, OR 100.0 %, J +29.91 Wh | stage 3: not needed (the best''s louver neighbours were evaluated)"},{"stage":"wind","set":{},"why":"wind 1.9 m/s below 15 m/s"},{"stage":"hold","set":{},"why":"no manual hold"},{"stage":"faults","set":{},"why":"no fault"},{"stage":"limits","set":{},"why":"louver -90..90 deg, dampers 0..100 %"},{"stage":"quantisation","set":{},"why":"louver onto the 18 deg motor grid, dampers onto 1 % steps"},{"stage":"rate","set":{},"why":"within rate limits"},{"stage":"regimes","set":{},"why":"regime 5 available"},{"stage":"occupancy","set":{"occupied":false,"source":"schedule"},"why":"unoccupied: no occupancy schedule"},{"stage":"comfort","set":{},"why":"unoccupied (no limit); direct sun 0 W/m2, DGPs 0.18, supply air none, asymmetry -1.6 K"}]','{"read":11.099,"quality":0.041,"estimate":2.277,"calibrate":0.018,"decide":20.553,"safety":0.116,"write":0.132,"predict":5.369,"comfort":0.553}',4.01579999999999941433e+01,0,NULL,NULL,NULL,120.0,'auto',NULL,NULL,NULL,NULL);
CREATE TABLE events (
    event_id INTEGER PRIMARY KEY AUTOINCREMENT,
    run_id INTEGER NOT NULL REFERENCES runs(run_id),
    cycle INTEGER NOT NULL,
    time_s REAL NOT NULL,
    level TEXT NOT NULL,
    kind TEXT NOT NULL,
    message TEXT NOT NULL
);
CREATE TABLE meta (
    key TEXT PRIMARY KEY,
    value TEXT NOT NULL
);
INSERT INTO "meta" VALUES('schema_version','6');
INSERT INTO "meta" VALUES('created_utc','2026-11-28T01:15:25Z');
CREATE TABLE model (
    run_id INTEGER NOT NULL REFERENCES runs(run_id),
    cycle INTEGER NOT NULL,
    time_s REAL NOT NULL,
    est_x1_c REAL,
    est_x2_c REAL,
    est_x3_c REAL,
    est_x4_c REAL,
    est_x5_c REAL,
    est_x6_c REAL,
    pred_x1_c REAL,
    pred_x2_c REAL,
    pred_x3_c REAL,
    pred_x4_c REAL,
    pred_x5_c REAL,
    pred_v_cav_ms REAL,
    q_cv_rd_w REAL,
    q_sol_trans_w REAL,
    q_air_w REAL,
    q_da_w REAL,
    horizon_s REAL,
    hz_x1_c REAL,
    hz_x2_c REAL,
    hz_x3_c REAL,
    hz_x4_c REAL,
    hz_x5_c REAL,
    applied_phi_deg REAL,
    applied_afr INTEGER,
    applied_or_pct REAL,
    plant_q_cv_rd_j REAL,
    plant_q_sol_trans_j REAL,
    plant_q_air_j REAL,
    plant_q_da_j REAL,
    PRIMARY KEY (run_id, cycle)
);
INSERT INTO "model" VALUES(1,1,1640964780.0,-1.05803709829640411042e+01,3.87458502340007271413e+00,18.7674995472795,-4.74923156819954783713e-01,-9.37429023082302137481e-01,1.13210422853397858484e+01,NULL,NULL,NULL,NULL,NULL,NULL,NULL,NULL,NULL,NULL,900.0,-7.10175823444154730168e+00,9.70192989802342253824e+00,1.83661401089937612596e+01,1.49402661612925271583e+01,1.86579351396111405847e+01,0.0,5,100.0,0.0,0.0,0.0,0.0);
INSERT INTO "model" VALUES(1,2,1640964840.0,-1.09696265680613578295e+01,4.00849858465863917444e+00,1.87191532040746437814e+01,-1.04692681393714792648e-01,-1.06021372578840100686e+00,1.13638258943666414779e+01,-1.02606588760540375917e+01,4.18428421561185359678e+00,1.86911518302674153346e+01,2.75904516270247768261e+00,1.61860498960214727048e+01,2.00903598632153540526e-01,-1.1945964474866926253e+02,0.0,0.0,0.0,900.0,-7.33769577074150447515e+00,9.78035407691197633539e+00,1.8350628018923714535e+01,1.44433388311917951796e+01,1.81120718337639345918e+01,0.0,5,100.0,-8.08667803922160328532e+03,0.0,0.0,0.0);
INSERT INTO "model" VALUES(1,3,1640964900.0,-1.06430097575795343798e+01,4.17956400067424738153e+00,1.86959426378164152993e+01,3.02151065387090511649e+00,1.43408771129311958243e+01,1.14377533192453029187e+01,-1.06273468848984293795e+01,4.31190281508588668657e+00,1.86338877742609270171e+01,2.47131490825637456509e+00,1.53920253137484905892e+01,2.00825475421732707603e-01,-1.07609006847529244056e+02,1.33398820050101250822e-02,0.0,2.02726977515331682755e-02,900.0,-7.34306335712403779325e+00,9.92844103689094481524e+00,1.82296195015004514061e+01,1.43494678151637344853e+01,17.5393713467393,0.0,5,100.0,-1.6172940622913925836e+04,6.71490444695034716104e-01,0.0,1.02046800887986610639e+00);
CREATE TABLE mqtt_cursor (
    destination TEXT PRIMARY KEY,
    run_id INTEGER NOT NULL DEFAULT 0,
    cycle INTEGER NOT NULL DEFAULT 0,
    time_s REAL,
    connected INTEGER NOT NULL DEFAULT 0,
    last_error TEXT NOT NULL DEFAULT '',
    last_error_utc TEXT,
    backlog INTEGER NOT NULL DEFAULT 0,
    delivered INTEGER NOT NULL DEFAULT 0,
    expired INTEGER NOT NULL DEFAULT 0,
    kpi_day TEXT,
    updated_utc TEXT NOT NULL
);
CREATE TABLE parameters (
    run_id INTEGER NOT NULL REFERENCES runs(run_id),
    cycle INTEGER NOT NULL,
    time_s REAL NOT NULL,
    source TEXT NOT NULL,
    h_out REAL, h_ca1 REAL, h_ca2 REAL, h_ca3 REAL, h_ca4 REAL, h_in REAL, f REAL, c REAL, n REAL,
    other TEXT NOT NULL DEFAULT '{}',
    cost REAL,
    detail TEXT NOT NULL DEFAULT '',
    PRIMARY KEY (run_id, cycle)
);
INSERT INTO "parameters" VALUES(1,1,1640964780.0,'prior',12.0,3.5,4.0,3.5,4.4,2.5,100.0,0.05,0.6,'{"q_x1":0.0,"q_x2":0.0,"q_x3":0.0,"q_x4":0.0}',NULL,'no calibration state at /tmp/s6/calibration.json: starting from the panel priors');
CREATE TABLE runs (
    run_id INTEGER PRIMARY KEY AUTOINCREMENT,
    panel TEXT NOT NULL,
    mode TEXT NOT NULL,
    started_utc TEXT NOT NULL,
    pid INTEGER NOT NULL,
    version TEXT NOT NULL,
    config_path TEXT,
    ended_utc TEXT,
    end_reason TEXT,
    cycles INTEGER,
    config_json TEXT
);
INSERT INTO "runs" VALUES(1,'suwon-south','dry run, simulated plant, lumped','2026-11-28T01:15:25Z',17425,'0.1.0','config/panels/suwon-south.yaml','2026-11-28T01:15:25Z','cycles done',3,'{"panel":{"id":"suwon-south","description":"Paper test unit, 250 mm cavity, black PVC louver"},"site":{"latitude_deg":37.3,"longitude_deg":127.0,"elevation_m":40.0,"utc_offset_h":9.0,"albedo":0.2,"terrain":"city","facade_height_m":5.0},"facade":{"azimuth_deg":180.0,"width_m":2.0,"glazed_height_m":2.5,"cavity_depth_m":0.25},"glazing":{"exterior":{"thickness_m":0.006,"solar_transmittance":0.6,"solar_reflectance_front":0.17,"solar_reflectance_back":0.22,"visible_transmittance":0.84,"visible_reflectance_front":0.055,"visible_reflectance_back":0.078,"emissivity_front":0.84,"emissivity_back":0.1,"density_kgm3":2500.0,"heat_capacity_jkgk":840.0},"interior_outer":{"thickness_m":0.006,"solar_transmittance":0.775,"solar_reflectance_front":0.071,"solar_reflectance_back":0.071,"visible_transmittance":0.881,"visible_reflectance_front":0.08,"visible_reflectance_back":0.08,"emissivity_front":0.84,"emissivity_back":0.84,"density_kgm3":2500.0,"heat_capacity_jkgk":840.0},"interior_inner":{"thickness_m":0.006,"solar_transmittance":0.6,"solar_reflectance_front":0.22,"solar_reflectance_back":0.17,"visible_transmittance":0.84,"visible_reflectance_front":0.078,"visible_reflectance_back":0.055,"emissivity_front":0.1,"emissivity_back":0.84,"density_kgm3":2500.0,"heat_capacity_jkgk":840.0},"interior_gap_m":0.012},"louver":{"slat_width_m":0.05,"slat_pitch_m":0.045,"slat_thickness_m":0.0015,"solar_reflectance_upper":0.07,"solar_reflectance_lower":0.07,"visible_reflectance_upper":0.05,"visible_reflectance_lower":0.05,"emissivity":0.9,"density_kgm3":1400.0,"heat_capacity_jkgk":1000.0,"segments":5,"step_deg":18.0},"openings":{"exterior_bottom":{"area_m2":0.5,"discharge_coefficient":0.6},"exterior_top":{"area_m2":0.5,"discharge_coefficient":0.6},"interior_bottom":{"area_m2":0.5,"discharge_coefficient":0.6},"interior_top":{"area_m2":0.5,"discharge_coefficient":0.6},"stack_height_m":2.75,"min_opening_ratio":0.01,"room_pressure_pa":0.0,"regularisation_pa":0.01,"wind_pressure":{"incidence_deg":[0,15,30,45,60,75,90,105,120,135,150,165,180],"cp_bottom":[0.644,0.609,0.527,0.336,0.103,-0.245,-0.532,-0.617,-0.594,-0.445,-0.383,-0.314,-0.299],"cp_top":[0.794,0.721,0.585,0.363,0.077,-0.299,-0.637,-0.749,-0.691,-0.538,-0.46,-0.368,-0.363]}},"room":{"t_in_c":22.0,"t_mrt_c":null,"floor_depth_m":6.0},"daylight":{"luminous_efficacy_lmw":110.0,"utilisation":0.3,"lighting_power_wm2":10.0,"illuminance_setpoint_lx":500.0},"occupancy":null,"comfort":{"category":"B","direct_sun_max_wm2":5.0,"dgp_max":0.35,"supply_air_min_c":null,"supply_air_speed_ms":0.15,"turbulence_pct":40.0,"occupant_distance_m":1.0,"eye_height_m":1.2,"asymmetry_height_m":0.6,"sill_height_m":0.0},"model":{"step_s":60.0,"coupling":"implicit","ping_pong_substeps":1,"coupling_tolerance_k":1e-06,"coupling_max_iterations":40,"zoh":"eig","sky_model":"swinbank","q_air_basis":"ventilation_credit","decomposition":"erbs","transposition":"haydavies","louver_flow_loss":true,"cavity_air_profile":"exponential","cavity_air_probe":"mean","diagonal_flow":"power_law","louver_diffuse":"sky_ground","air_density_kgm3":1.19,"air_heat_capacity_jkgk":1006.0},"parameters":{"h_out":{"default":12.0,"lower":3.0,"upper":40.0},"h_ca1":{"default":3.5,"lower":1.0,"upper":15.0},"h_ca2":{"default":4.0,"lower":1.0,"upper":20.0},"h_ca3":{"default":3.5,"lower":1.0,"upper":15.0},"h_ca4":{"default":4.4,"lower":2.0,"upper":8.0},"h_in":{"default":2.5,"lower":1.0,"upper":8.0},"f":{"default":100.0,"lower":5.0,"upper":10000.0},"c":{"default":0.05,"lower":0.002,"upper":0.5},"n":{"default":0.6,"lower":0.5,"upper":1.0}},"calibration":{"window_h":4.0,"forgetting_factor":0.7,"horizon_steps":15,"start_stride_steps":4,"start_smoothing_s":480.0,"update_interval_s":600.0,"min_window_h":1.0,"max_nfev":8,"broyden_updates":1,"offline_max_nfev":40,"flow_from_velocity":true,"loss":"soft_l1","f_scale":1.0,"temperature_scale_k":0.3,"velocity_scale_ms":0.01,"adaptive_scales":true,"prior_weight":1.0,"identifiability_sd_ratio":1.0,"prior_log_sd":0.7,"prior_sd_n":0.15,"drift_log_sd_per_h":0.05,"heat_offsets":true,"offset_sd_wm2":20.0,"offset_bound_wm2":200.0,"offset_drift_wm2_per_h":20.0,"offset_tracking_s":600.0,"innovation_smoothing_s":[300.0,1800.0,1800.0,300.0],"reading_offset_tracking_s":[0.0,0.0,0.0,300.0,300.0],"reading_offset_memory_s":3600.0,"measurement_gain":[1.0,0.3,0.3,1.0,1.0],"spike_threshold_k":3.0,"fixed":[]},"control":{"mode":"auto","auto_heating_below_c":15.0,"horizon_steps":15,"optimiser":"mpc","or_grid_pct":[0.0,100.0],"or_refine_points":2,"or_refine_rounds":0,"flat_tolerance_pct":0.01,"refine_max_pairs":1,"screening_step_s":300.0,"screening_tolerance_k":0.1,"coupling_tolerance_k":0.0001,"full_candidates":8,"louver_neighbours":2,"finalist_margin_pct":20.0,"louver_move_penalty_wh":0.1,"time_budget_s":20.0,"baseline":{"sun_threshold_wm2":20.0,"night_angle_deg":90.0,"heating_open_above_room_k":2.0,"hysteresis_k":1.0,"cooling_flush_above_outdoor_k":1.0,"night_cooling_below_room_k":3.0}},"devices":{"read_budget_s":15.0,"write_budget_s":10.0,"entries":[{"name":"facade-io","kind":"modbus_tcp","tcp":{"host":"192.168.10.20","port":502},"serial":null,"device_id":1,"timeout_s":1.0,"retries":1,"reconnect_backoff_min_s":1.0,"reconnect_backoff_max_s":60.0,"breaker_failures":2,"breaker_cycles":5,"max_read_gap":0,"sensors":[{"signal":"x1_c","address":0,"data_type":"int16","word_order":"big","byte_order":"big","scale":0.1,"offset":0.0,"table":"input","nan_value":-32768},{"signal":"x2_c","address":1,"data_type":"int16","word_order":"big","byte_order":"big","scale":0.1,"offset":0.0,"table":"input","nan_value":-32768},{"signal":"x3_c","address":2,"data_type":"int16","word_order":"big","byte_order":"big","scale":0.1,"offset":0.0,"table":"input","nan_value":-32768},{"signal":"x4_c","address":3,"data_type":"int16","word_order":"big","byte_order":"big","scale":0.1,"offset":0.0,"table":"input","nan_value":-32768},{"signal":"x5_c","address":4,"data_type":"int16","word_order":"big","byte_order":"big","scale":0.1,"offset":0.0,"table":"input","nan_value":-32768},{"signal":"t_room_c","address":5,"data_type":"int16","word_order":"big","byte_order":"big","scale":0.1,"offset":0.0,"table":"input","nan_value":-32768},{"signal":"v_cav_ms","address":6,"data_type":"uint16","word_order":"big","byte_order":"big","scale":0.001,"offset":0.0,"table":"input","nan_value":65535}],"actuators":[{"signal":"phi_deg","address":100,"data_type":"int16","word_order":"big","byte_order":"big","scale":1.0,"offset":0.0,"table":"holding","feedback":null},{"signal":"afr","address":101,"data_type":"uint16","word_order":"big","byte_order":"big","scale":1.0,"offset":0.0,"table":"holding","feedback":null},{"signal":"or_pct","address":102,"data_type":"uint16","word_order":"big","byte_order":"big","scale":0.1,"offset":0.0,"table":"holding","feedback":null}],"override_input":null},{"name":"weather","kind":"serial_station","tcp":null,"serial":{"port":"/dev/ttyUSB0","baudrate":9600,"bytesize":8,"parity":"N","stopbits":1},"device_id":1,"timeout_s":2.0,"retries":1,"reconnect_backoff_min_s":1.0,"reconnect_backoff_max_s":60.0,"breaker_failures":2,"breaker_cycles":5,"max_read_gap":0,"sensors":[],"actuators":[],"override_input":null}]},"daemon":{"state_directory":null,"cycle_period_s":60.0,"calibrate_budget_s":10.0,"store_budget_s":5.0,"store_buffer_cycles":720,"room_temperature_source":"auto","max_predicted_cycles":10,"quality":{"stuck_window":15,"stuck_signals":["x1_c","x2_c","x3_c","x4_c","x5_c","t_out_c"],"max_rate_k_per_min":10.0,"rate_signals":["x1_c","x2_c","x3_c","t_room_c","t_out_c"],"max_sample_age_s":30.0},"metrics_file":null},"safety":{"safe_state":{"phi_deg":90.0,"afr":10,"or_pct":0.0},"fault_signals":["t_out_c","ghi_wm2"],"wind_limit_ms":15.0,"wind_hysteresis_ms":3.0,"wind_release_cycles":10,"wind_safe_angle_deg":90.0,"wind_close_exterior":true,"wind_unknown":"safe","phi_min_deg":-90.0,"phi_max_deg":90.0,"or_max_pct":100.0,"or_step_pct":1.0,"or_deadband_pct":5.0,"min_louver_move_interval_s":300.0,"manual_hold_min":120.0,"manual_reset_local":null},"mqtt":null,"bacnet":null}');
CREATE TABLE samples (
    run_id INTEGER NOT NULL REFERENCES runs(run_id),
    cycle INTEGER NOT NULL,
    time_s REAL NOT NULL,
    signal TEXT NOT NULL,
    value REAL,
    quality TEXT NOT NULL,
    detail TEXT NOT NULL DEFAULT '',
    PRIMARY KEY (run_id, cycle, signal)
) WITHOUT ROWID;
INSERT INTO "samples" VALUES(1,1,1640964780.0,'ghi_wm2',0.0,'good','');
INSERT INTO "samples" VALUES(1,1,1640964780.0,'pressure_hpa',1.00485148419003337497e+03,'good','');
INSERT INTO "samples" VALUES(1,1,1640964780.0,'rh_pct',9.68895619708190594145e+01,'good','');
INSERT INTO "samples" VALUES(1,1,1640964780.0,'t_out_c',-9.9923328350434861278e+00,'good','');
INSERT INTO "samples" VALUES(1,1,1640964780.0,'t_room_c',2.20097425781079252264e+01,'good','');
INSERT INTO "samples" VALUES(1,1,1640964780.0,'v_cav_ms',2.53889936249101621362e-03,'good','');
INSERT INTO "samples" VALUES(1,1,1640964780.0,'wind_dir_deg',1.87126869000436286682e+01,'good','');
INSERT INTO "samples" VALUES(1,1,1640964780.0,'wind_speed_ms',1.84795405892465880448e+00,'good','');
INSERT INTO "samples" VALUES(1,1,1640964780.0,'x1_c',-1.05803709829640339994e+01,'good','');
INSERT INTO "samples" VALUES(1,1,1640964780.0,'x2_c',3.87458502340009403042e+00,'good','');
INSERT INTO "samples" VALUES(1,1,1640964780.0,'x3_c',1.87674995472795202999e+01,'good','');
INSERT INTO "samples" VALUES(1,1,1640964780.0,'x4_c',-4.74923156819933467431e-01,'good','');
INSERT INTO "samples" VALUES(1,1,1640964780.0,'x5_c',-9.37429023082287926627e-01,'good','');
INSERT INTO "samples" VALUES(1,2,1640964840.0,'ghi_wm2',0.0,'good','');
INSERT INTO "samples" VALUES(1,2,1640964840.0,'pressure_hpa',1.00498414124542227905e+03,'good','');
INSERT INTO "samples" VALUES(1,2,1640964840.0,'rh_pct',9.80666058428535336588e+01,'good','');
INSERT INTO "samples" VALUES(1,2,1640964840.0,'t_out_c',-1.02304729727116328064e+01,'good','');
INSERT INTO "samples" VALUES(1,2,1640964840.0,'t_room_c',2.1993216029972359137e+01,'good','');
INSERT INTO "samples" VALUES(1,2,1640964840.0,'v_cav_ms',1.13671253099238631079e-01,'good','');
INSERT INTO "samples" VALUES(1,2,1640964840.0,'wind_dir_deg',2.28590101947345338819e+01,'good','');
INSERT INTO "samples" VALUES(1,2,1640964840.0,'wind_speed_ms',1.80460917582427415872e+00,'good','');
INSERT INTO "samples" VALUES(1,2,1640964840.0,'x1_c',-1.09696265680613382899e+01,'good','');
INSERT INTO "samples" VALUES(1,2,1640964840.0,'x2_c',3.59833211243447737004e+00,'good','');
INSERT INTO "samples" VALUES(1,2,1640964840.0,'x3_c',1.87844897429582360359e+01,'good','');
INSERT INTO "samples" VALUES(1,2,1640964840.0,'x4_c',-1.0469268139369984627e-01,'good','');
INSERT INTO "samples" VALUES(1,2,1640964840.0,'x5_c',-1.06021372578840589184e+00,'good','');
INSERT INTO "samples" VALUES(1,3,1640964900.0,'ghi_wm2',5.4270988164405578602e-02,'good','');
INSERT INTO "samples" VALUES(1,3,1640964900.0,'pressure_hpa',1.00492803785535215869e+03,'good','');
INSERT INTO "samples" VALUES(1,3,1640964900.0,'rh_pct',96.75342374913,'good','');
INSERT INTO "samples" VALUES(1,3,1640964900.0,'t_out_c',-1.03526663203500017833e+01,'good','');
INSERT INTO "samples" VALUES(1,3,1640964900.0,'t_room_c',2.16207116952440756571e+01,'good','');
INSERT INTO "samples" VALUES(1,3,1640964900.0,'v_cav_ms',2.24440219780722594045e-01,'good','');
INSERT INTO "samples" VALUES(1,3,1640964900.0,'wind_dir_deg',2.03938513964047523079e+01,'good','');
INSERT INTO "samples" VALUES(1,3,1640964900.0,'wind_speed_ms',1.89571082072867280743e+00,'good','');
INSERT INTO "samples" VALUES(1,3,1640964900.0,'x1_c',-1.06430097575795077344e+01,'good','');
INSERT INTO "samples" VALUES(1,3,1640964900.0,'x2_c',3.8707734337137233993e+00,'good','');
INSERT INTO "samples" VALUES(1,3,1640964900.0,'x3_c',1.88407373194459601961e+01,'good','');
INSERT INTO "samples" VALUES(1,3,1640964900.0,'x4_c',2.5024030514895438948e+00,'good','');
INSERT INTO "samples" VALUES(1,3,1640964900.0,'x5_c',1.37970693721651240795e+01,'good','');
CREATE INDEX samples_by_time ON samples (time_s, signal);
CREATE INDEX decisions_by_time ON decisions (time_s);
CREATE INDEX comfort_by_time ON comfort (time_s);
CREATE INDEX commands_pending ON commands (status, command_id);
DELETE FROM "sqlite_sequence";
INSERT INTO "sqlite_sequence" VALUES('runs',1);
COMMIT;
