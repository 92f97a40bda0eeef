-- A real schema-7 database: 'dsfd run' of the test harness's Suwon panel (no devices;
-- calibration.window_h 1, min_window_h 0.2, update_interval_s 300: two on-line updates)
-- --dry-run --plant sim --plant-fidelity lumped --start 2022-01-01T23:30:00Z --cycles 20 of
-- dsfd at commit c30ab03 (before schema 8), dumped with Python's sqlite3 iterdump;
-- tests/storage/test_parameter_sd_migration.py rebuilds it.
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
INSERT INTO "comfort" VALUES(1,1,1641079800.0,0,'schedule',7.62205114667049201662e+01,1.0,4.35209528188196941283e+01,3.91803652808567903775e+00,5.0,0.35,1.84451722585695776501e+01,23.0,'[]');
INSERT INTO "comfort" VALUES(1,2,1641079860.0,0,'schedule',7.43266531786769490963e+01,1.0,3.02033166887960078392e+01,3.86672050982525661311e+00,5.0,0.35,1.84451722585695776501e+01,23.0,'[]');
INSERT INTO "comfort" VALUES(1,3,1641079920.0,0,'schedule',78.761518256254,1.0,2.93721836015074018177e+01,3.72518899952228821348e+00,5.0,0.35,1.84451722585695776501e+01,23.0,'[]');
INSERT INTO "comfort" VALUES(1,4,1641079980.0,0,'schedule',81.0374844204264,1.0,2.46150656551712359036e+01,3.85707278585505264345e+00,5.0,0.35,1.84451722585695776501e+01,23.0,'[]');
INSERT INTO "comfort" VALUES(1,5,1641080040.0,0,'schedule',8.08932848228984795451e+01,1.0,2.42248146362812804004e+01,3.86768805667628612354e+00,5.0,0.35,1.84451722585695776501e+01,23.0,'[]');
INSERT INTO "comfort" VALUES(1,6,1641080100.0,0,'schedule',8.51552193970560722391e+01,1.0,2.57934500648898961121e+01,3.7560059538818677538e+00,5.0,0.35,1.84451722585695776501e+01,23.0,'[]');
INSERT INTO "comfort" VALUES(1,7,1641080160.0,0,'schedule',8.75136620596772445406e+01,1.0,2.56865048739799135542e+01,3.98854944122098231673e+00,5.0,0.35,1.84451722585695776501e+01,23.0,'[]');
INSERT INTO "comfort" VALUES(1,8,1641080220.0,0,'schedule',90.1078795657938,1.0,2.61346475853392234967e+01,3.85779518935095211418e+00,5.0,0.35,1.84451722585695776501e+01,23.0,'[]');
INSERT INTO "comfort" VALUES(1,9,1641080280.0,0,'schedule',9.10615559691743783367e+01,1.0,2.68716411275140671928e+01,4.0172458605158,5.0,0.35,1.84451722585695776501e+01,23.0,'[]');
INSERT INTO "comfort" VALUES(1,10,1641080340.0,0,'schedule',9.26962786078997567039e+01,1.0,1.1021155809739980214e+01,4.01603876406875315296e+00,5.0,0.35,1.84451722585695776501e+01,23.0,'[]');
INSERT INTO "comfort" VALUES(1,11,1641080400.0,0,'schedule',94.5433478929728,1.0,2.79245653319877646931e+01,3.98883986321999373103e+00,5.0,0.35,1.84451722585695776501e+01,23.0,'[]');
INSERT INTO "comfort" VALUES(1,12,1641080460.0,0,'schedule',9.50511912248831265532e+01,1.0,2.74009600719432455662e+01,3.84214460021513559695e+00,5.0,0.35,1.84451722585695776501e+01,23.0,'[]');
INSERT INTO "comfort" VALUES(1,13,1641080520.0,0,'schedule',9.66152873472130551118e+01,1.0,2.72297672806677724119e+01,3.68096358788636734971e+00,5.0,0.35,1.84451722585695776501e+01,23.0,'[]');
INSERT INTO "comfort" VALUES(1,14,1641080580.0,0,'schedule',9.66762245862843911953e+01,1.0,2.68750894789031917757e+01,3.95034068069196564465e+00,5.0,0.35,1.84451722585695776501e+01,23.0,'[]');
INSERT INTO "comfort" VALUES(1,15,1641080640.0,0,'schedule',9.72744179506101573889e+01,1.0,2.69843948683786720725e+01,3.8033760809601631081e+00,5.0,0.35,1.84451722585695776501e+01,23.0,'[]');
INSERT INTO "comfort" VALUES(1,16,1641080700.0,0,'schedule',9.73121289965972664521e+01,1.0,2.68636949435999667907e+01,3.81124995913018,5.0,0.35,1.84451722585695776501e+01,23.0,'[]');
INSERT INTO "comfort" VALUES(1,17,1641080760.0,0,'schedule',1.02302787885450825907e+02,1.0,2.65428718425112037944e+01,4.07677309028383660916e+00,5.0,0.35,1.84451722585695776501e+01,23.0,'[]');
INSERT INTO "comfort" VALUES(1,18,1641080820.0,0,'schedule',1.00182107993938345207e+02,1.0,2.55915737607328424023e+01,3.94057092868575864486e+00,5.0,0.35,1.84451722585695776501e+01,23.0,'[]');
INSERT INTO "comfort" VALUES(1,19,1641080880.0,0,'schedule',1.02176814390731649949e+02,1.0,2.63086882490233051621e+01,3.81567410871969059371e+00,5.0,0.35,1.84451722585695776501e+01,23.0,'[]');
INSERT INTO "comfort" VALUES(1,20,1641080940.0,0,'schedule',1.0441069015540414e+02,1.0,2.59578572797414040005e+01,3.84854486405487250522e+00,5.0,0.35,1.84451722585695776501e+01,23.0,'[]');
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
INSERT INTO "decisions" VALUES(1,1,0,1641079800.0,'2022-01-01T23:30:00Z','mpc','',1,-4.7876158741851767989e+05,18.0,1,100.0,18.0,1,100.0,'verified','[]','[{"stage":"decide:mpc","set":{"phi_deg":18.0,"afr":1,"or_pct":100.0},"why":"candidates: 11 louver positions x 6 damper sets (regimes [1, 3, 5, 6, 9, 10]), OR grid [0.0, 100.0] % | stage 1: screened 121 candidates at 300 s steps | stage 2: 11 at full resolution (10 finalists, OR brackets of 1 pairs), best louver +18 deg, regime 1, OR 100.0 %, J -132.99 Wh | stage 3: not needed (the best''s louver neighbours were evaluated)"},{"stage":"wind","set":{},"why":"wind 5.7 m/s below 15 m/s"},{"stage":"hold","set":{},"why":"no manual hold"},{"stage":"faults","set":{},"why":"no fault"},{"stage":"limits","set":{},"why":"louver -90..90 deg, dampers 0..100 %"},{"stage":"quantisation","set":{},"why":"louver onto the 18 deg motor grid, dampers onto 1 % steps"},{"stage":"rate","set":{},"why":"within rate limits"},{"stage":"regimes","set":{},"why":"regime 1 available"},{"stage":"occupancy","set":{"occupied":false,"source":"schedule"},"why":"unoccupied: no occupancy schedule"},{"stage":"comfort","set":{},"why":"unoccupied (no limit); direct sun 76 W/m2, DGPs 1.00, supply air 43.5 \u00b0C, asymmetry +3.9 K"}]','{"read":2.104,"quality":0.051,"estimate":1.235,"calibrate":0.016,"decide":28.745,"safety":0.13,"write":0.145,"predict":8.061,"comfort":1.288}',4.17750000000000056834e+01,0,NULL,NULL,NULL,0.0,'auto',NULL,NULL,NULL,NULL);
INSERT INTO "decisions" VALUES(1,2,1,1641079860.0,'2022-01-01T23:31:00Z','mpc','',1,-4.42663375167290912932e+05,18.0,1,100.0,18.0,1,100.0,'verified','[]','[{"stage":"decide:mpc","set":{"phi_deg":18.0,"afr":1,"or_pct":100.0},"why":"candidates: 11 louver positions x 6 damper sets (regimes [1, 3, 5, 6, 9, 10]), OR grid [0.0, 100.0] % | stage 1: screened 121 candidates at 300 s steps | stage 2: 12 at full resolution (10 finalists, OR brackets of 1 pairs), best louver +18 deg, regime 1, OR 100.0 %, J -122.96 Wh | stage 3: not needed (the best''s louver neighbours were evaluated)"},{"stage":"wind","set":{},"why":"wind 5.1 m/s below 15 m/s"},{"stage":"hold","set":{},"why":"no manual hold"},{"stage":"faults","set":{},"why":"no fault"},{"stage":"limits","set":{},"why":"louver -90..90 deg, dampers 0..100 %"},{"stage":"quantisation","set":{},"why":"louver onto the 18 deg motor grid, dampers onto 1 % steps"},{"stage":"rate","set":{},"why":"within rate limits"},{"stage":"regimes","set":{},"why":"regime 1 available"},{"stage":"occupancy","set":{"occupied":false,"source":"schedule"},"why":"unoccupied: no occupancy schedule"},{"stage":"comfort","set":{},"why":"unoccupied (no limit); direct sun 74 W/m2, DGPs 1.00, supply air 30.2 \u00b0C, asymmetry +3.9 K"}]','{"read":34.278,"quality":0.043,"estimate":2.458,"calibrate":0.018,"decide":24.551,"safety":0.128,"write":0.148,"predict":3.271,"comfort":0.585}',6.54799999999999897664e+01,0,NULL,NULL,NULL,60.0,'auto',NULL,NULL,NULL,NULL);
INSERT INTO "decisions" VALUES(1,3,2,1641079920.0,'2022-01-01T23:32:00Z','mpc','',1,-4.39186051691949134708e+05,18.0,7,100.0,18.0,7,100.0,'verified','[]','[{"stage":"decide:mpc","set":{"phi_deg":18.0,"afr":7,"or_pct":100.0},"why":"candidates: 11 louver positions x 6 damper sets (regimes [1, 3, 5, 6, 9, 10]), OR grid [0.0, 100.0] % | stage 1: screened 121 candidates at 300 s steps | stage 2: 13 at full resolution (10 finalists, OR brackets of 1 pairs), best louver +18 deg, regime 7, OR 100.0 %, J -122.00 Wh | stage 3: not needed (the best''s louver neighbours were evaluated)"},{"stage":"wind","set":{},"why":"wind 4.4 m/s below 15 m/s"},{"stage":"hold","set":{},"why":"no manual hold"},{"stage":"faults","set":{},"why":"no fault"},{"stage":"limits","set":{},"why":"louver -90..90 deg, dampers 0..100 %"},{"stage":"quantisation","set":{},"why":"louver onto the 18 deg motor grid, dampers onto 1 % steps"},{"stage":"rate","set":{},"why":"within rate limits"},{"stage":"regimes","set":{},"why":"regime 7 available"},{"stage":"occupancy","set":{"occupied":false,"source":"schedule"},"why":"unoccupied: no occupancy schedule"},{"stage":"comfort","set":{},"why":"unoccupied (no limit); direct sun 79 W/m2, DGPs 1.00, supply air 29.4 \u00b0C, asymmetry +3.7 K"}]','{"read":8.267,"quality":0.039,"estimate":2.439,"calibrate":0.023,"decide":23.355,"safety":0.124,"write":0.148,"predict":3.482,"comfort":0.579}',38.456,0,NULL,NULL,NULL,120.0,'auto',NULL,NULL,NULL,NULL);
INSERT INTO "decisions" VALUES(1,4,3,1641079980.0,'2022-01-01T23:33:00Z','mpc','',1,-4.58835291749259689816e+05,18.0,7,100.0,18.0,7,100.0,'verified','[]','[{"stage":"decide:mpc","set":{"phi_deg":18.0,"afr":7,"or_pct":100.0},"why":"candidates: 11 louver positions x 6 damper sets (regimes [1, 3, 5, 6, 9, 10]), OR grid [0.0, 100.0] % | stage 1: screened 121 candidates at 300 s steps | stage 2: 11 at full resolution (10 finalists, OR brackets of 1 pairs), best louver +18 deg, regime 7, OR 100.0 %, J -127.45 Wh | stage 3: not needed (the best''s louver neighbours were evaluated)"},{"stage":"wind","set":{},"why":"wind 3.9 m/s below 15 m/s"},{"stage":"hold","set":{},"why":"no manual hold"},{"stage":"faults","set":{},"why":"no fault"},{"stage":"limits","set":{},"why":"louver -90..90 deg, dampers 0..100 %"},{"stage":"quantisation","set":{},"why":"louver onto the 18 deg motor grid, dampers onto 1 % steps"},{"stage":"rate","set":{},"why":"within rate limits"},{"stage":"regimes","set":{},"why":"regime 7 available"},{"stage":"occupancy","set":{"occupied":false,"source":"schedule"},"why":"unoccupied: no occupancy schedule"},{"stage":"comfort","set":{},"why":"unoccupied (no limit); direct sun 81 W/m2, DGPs 1.00, supply air 24.6 \u00b0C, asymmetry +3.9 K"}]','{"read":28.83,"quality":0.043,"estimate":7.356,"calibrate":0.035,"decide":26.639,"safety":0.203,"write":0.199,"predict":4.224,"comfort":0.639}',6.81679999999999921547e+01,0,NULL,NULL,NULL,180.0,'auto',NULL,NULL,NULL,NULL);
INSERT INTO "decisions" VALUES(1,5,4,1641080040.0,'2022-01-01T23:34:00Z','mpc','',1,-4.76323517112311616093e+05,18.0,7,100.0,18.0,7,100.0,'verified','[]','[{"stage":"decide:mpc","set":{"phi_deg":18.0,"afr":7,"or_pct":100.0},"why":"candidates: 11 louver positions x 6 damper sets (regimes [1, 3, 5, 6, 9, 10]), OR grid [0.0, 100.0] % | stage 1: screened 121 candidates at 300 s steps | stage 2: 11 at full resolution (10 finalists, OR brackets of 1 pairs), best louver +18 deg, regime 7, OR 100.0 %, J -132.31 Wh | stage 3: not needed (the best''s louver neighbours were evaluated)"},{"stage":"wind","set":{},"why":"wind 3.2 m/s below 15 m/s"},{"stage":"hold","set":{},"why":"no manual hold"},{"stage":"faults","set":{},"why":"no fault"},{"stage":"limits","set":{},"why":"louver -90..90 deg, dampers 0..100 %"},{"stage":"quantisation","set":{},"why":"louver onto the 18 deg motor grid, dampers onto 1 % steps"},{"stage":"rate","set":{},"why":"within rate limits"},{"stage":"regimes","set":{},"why":"regime 7 available"},{"stage":"occupancy","set":{"occupied":false,"source":"schedule"},"why":"unoccupied: no occupancy schedule"},{"stage":"comfort","set":{},"why":"unoccupied (no limit); direct sun 81 W/m2, DGPs 1.00, supply air 24.2 \u00b0C, asymmetry +3.9 K"}]','{"read":20.346,"quality":0.04,"estimate":2.782,"calibrate":0.033,"decide":22.503,"safety":0.121,"write":0.149,"predict":3.517,"comfort":0.6}',5.00910000000000081837e+01,0,NULL,NULL,NULL,240.0,'auto',NULL,NULL,NULL,NULL);
INSERT INTO "decisions" VALUES(1,6,5,1641080100.0,'2022-01-01T23:35:00Z','mpc','',1,-4.75979316936423536409e+05,18.0,7,100.0,18.0,7,100.0,'verified','[]','[{"stage":"decide:mpc","set":{"phi_deg":18.0,"afr":7,"or_pct":100.0},"why":"candidates: 11 louver positions x 6 damper sets (regimes [1, 3, 5, 6, 9, 10]), OR grid [0.0, 100.0] % | stage 1: screened 121 candidates at 300 s steps | stage 2: 11 at full resolution (10 finalists, OR brackets of 1 pairs), best louver +18 deg, regime 7, OR 100.0 %, J -132.22 Wh | stage 3: not needed (the best''s louver neighbours were evaluated)"},{"stage":"wind","set":{},"why":"wind 3.4 m/s below 15 m/s"},{"stage":"hold","set":{},"why":"no manual hold"},{"stage":"faults","set":{},"why":"no fault"},{"stage":"limits","set":{},"why":"louver -90..90 deg, dampers 0..100 %"},{"stage":"quantisation","set":{},"why":"louver onto the 18 deg motor grid, dampers onto 1 % steps"},{"stage":"rate","set":{},"why":"within rate limits"},{"stage":"regimes","set":{},"why":"regime 7 available"},{"stage":"occupancy","set":{"occupied":false,"source":"schedule"},"why":"unoccupied: no occupancy schedule"},{"stage":"comfort","set":{},"why":"unoccupied (no limit); direct sun 85 W/m2, DGPs 1.00, supply air 25.8 \u00b0C, asymmetry +3.8 K"}]','{"read":20.754,"quality":0.041,"estimate":7.21,"calibrate":0.035,"decide":22.97,"safety":0.156,"write":0.164,"predict":3.79,"comfort":0.587}',5.57070000000000078435e+01,0,NULL,NULL,NULL,300.0,'auto',NULL,NULL,NULL,NULL);
INSERT INTO "decisions" VALUES(1,7,6,1641080160.0,'2022-01-01T23:36:00Z','mpc','',1,-4.38394722048812545854e+05,18.0,7,100.0,18.0,7,100.0,'verified','[]','[{"stage":"decide:mpc","set":{"phi_deg":18.0,"afr":7,"or_pct":100.0},"why":"candidates: 11 louver positions x 6 damper sets (regimes [1, 3, 5, 6, 9, 10]), OR grid [0.0, 100.0] % | stage 1: screened 121 candidates at 300 s steps | stage 2: 11 at full resolution (10 finalists, OR brackets of 1 pairs), best louver +18 deg, regime 7, OR 100.0 %, J -121.78 Wh | stage 3: not needed (the best''s louver neighbours were evaluated)"},{"stage":"wind","set":{},"why":"wind 3.6 m/s below 15 m/s"},{"stage":"hold","set":{},"why":"no manual hold"},{"stage":"faults","set":{},"why":"no fault"},{"stage":"limits","set":{},"why":"louver -90..90 deg, dampers 0..100 %"},{"stage":"quantisation","set":{},"why":"louver onto the 18 deg motor grid, dampers onto 1 % steps"},{"stage":"rate","set":{},"why":"within rate limits"},{"stage":"regimes","set":{},"why":"regime 7 available"},{"stage":"occupancy","set":{"occupied":false,"source":"schedule"},"why":"unoccupied: no occupancy schedule"},{"stage":"comfort","set":{},"why":"unoccupied (no limit); direct sun 88 W/m2, DGPs 1.00, supply air 25.7 \u00b0C, asymmetry +4.0 K"}]','{"read":11.481,"quality":0.041,"estimate":2.595,"calibrate":0.099,"decide":23.076,"safety":0.115,"write":0.145,"predict":3.085,"comfort":0.714}',4.13510000000000061976e+01,0,NULL,NULL,NULL,360.0,'auto',NULL,NULL,NULL,NULL);
INSERT INTO "decisions" VALUES(1,8,7,1641080220.0,'2022-01-01T23:37:00Z','mpc','',1,-4.33654916903753881321e+05,18.0,7,100.0,18.0,7,100.0,'verified','[]','[{"stage":"decide:mpc","set":{"phi_deg":18.0,"afr":7,"or_pct":100.0},"why":"candidates: 11 louver positions x 6 damper sets (regimes [1, 3, 5, 6, 9, 10]), OR grid [0.0, 100.0] % | stage 1: screened 121 candidates at 300 s steps | stage 2: 11 at full resolution (10 finalists, OR brackets of 1 pairs), best louver +18 deg, regime 7, OR 100.0 %, J -120.46 Wh | stage 3: not needed (the best''s louver neighbours were evaluated)"},{"stage":"wind","set":{},"why":"wind 3.8 m/s below 15 m/s"},{"stage":"hold","set":{},"why":"no manual hold"},{"stage":"faults","set":{},"why":"no fault"},{"stage":"limits","set":{},"why":"louver -90..90 deg, dampers 0..100 %"},{"stage":"quantisation","set":{},"why":"louver onto the 18 deg motor grid, dampers onto 1 % steps"},{"stage":"rate","set":{},"why":"within rate limits"},{"stage":"regimes","set":{},"why":"regime 7 available"},{"stage":"occupancy","set":{"occupied":false,"source":"schedule"},"why":"unoccupied: no occupancy schedule"},{"stage":"comfort","set":{},"why":"unoccupied (no limit); direct sun 90 W/m2, DGPs 1.00, supply air 26.1 \u00b0C, asymmetry +3.9 K"}]','{"read":11.052,"quality":0.044,"estimate":4.481,"calibrate":0.035,"decide":31.166,"safety":0.187,"write":0.167,"predict":3.873,"comfort":1.046}',5.20509999999999948281e+01,0,NULL,NULL,NULL,420.0,'auto',NULL,NULL,NULL,NULL);
INSERT INTO "decisions" VALUES(1,9,8,1641080280.0,'2022-01-01T23:38:00Z','mpc','',1,-4.15833589508928591366e+05,18.0,1,100.0,18.0,1,100.0,'verified','[]','[{"stage":"decide:mpc","set":{"phi_deg":18.0,"afr":1,"or_pct":100.0},"why":"candidates: 11 louver positions x 6 damper sets (regimes [1, 3, 5, 6, 9, 10]), OR grid [0.0, 100.0] % | stage 1: screened 121 candidates at 300 s steps | stage 2: 13 at full resolution (10 finalists, OR brackets of 1 pairs), best louver +18 deg, regime 1, OR 100.0 %, J -115.51 Wh | stage 3: not needed (the best''s louver neighbours were evaluated)"},{"stage":"wind","set":{},"why":"wind 4.1 m/s below 15 m/s"},{"stage":"hold","set":{},"why":"no manual hold"},{"stage":"faults","set":{},"why":"no fault"},{"stage":"limits","set":{},"why":"louver -90..90 deg, dampers 0..100 %"},{"stage":"quantisation","set":{},"why":"louver onto the 18 deg motor grid, dampers onto 1 % steps"},{"stage":"rate","set":{},"why":"within rate limits"},{"stage":"regimes","set":{},"why":"regime 1 available"},{"stage":"occupancy","set":{"occupied":false,"source":"schedule"},"why":"unoccupied: no occupancy schedule"},{"stage":"comfort","set":{},"why":"unoccupied (no limit); direct sun 91 W/m2, DGPs 1.00, supply air 26.9 \u00b0C, asymmetry +4.0 K"}]','{"read":15.187,"quality":0.04,"estimate":6.878,"calibrate":0.018,"decide":24.767,"safety":0.103,"write":0.125,"predict":2.63,"comfort":0.636}',5.03840000000000074473e+01,0,NULL,NULL,NULL,480.0,'auto',NULL,NULL,NULL,NULL);
INSERT INTO "decisions" VALUES(1,10,9,1641080340.0,'2022-01-01T23:39:00Z','mpc','',1,-3.97416513625375053386e+05,18.0,1,100.0,18.0,1,100.0,'verified','[]','[{"stage":"decide:mpc","set":{"phi_deg":18.0,"afr":1,"or_pct":100.0},"why":"candidates: 11 louver positions x 6 damper sets (regimes [1, 3, 5, 6, 9, 10]), OR grid [0.0, 100.0] % | stage 1: screened 121 candidates at 300 s steps | stage 2: 12 at full resolution (10 finalists, OR brackets of 1 pairs), best louver +18 deg, regime 1, OR 100.0 %, J -110.39 Wh | stage 3: not needed (the best''s louver neighbours were evaluated)"},{"stage":"wind","set":{},"why":"wind 4.6 m/s below 15 m/s"},{"stage":"hold","set":{},"why":"no manual hold"},{"stage":"faults","set":{},"why":"no fault"},{"stage":"limits","set":{},"why":"louver -90..90 deg, dampers 0..100 %"},{"stage":"quantisation","set":{},"why":"louver onto the 18 deg motor grid, dampers onto 1 % steps"},{"stage":"rate","set":{},"why":"within rate limits"},{"stage":"regimes","set":{},"why":"regime 1 available"},{"stage":"occupancy","set":{"occupied":false,"source":"schedule"},"why":"unoccupied: no occupancy schedule"},{"stage":"comfort","set":{},"why":"unoccupied (no limit); direct sun 93 W/m2, DGPs 1.00, supply air 11.0 \u00b0C, asymmetry +4.0 K"}]','{"read":21.064,"quality":0.04,"estimate":2.22,"calibrate":0.016,"decide":26.236,"safety":0.1,"write":0.123,"predict":2.805,"comfort":4.872}',5.74759999999999919833e+01,0,NULL,NULL,NULL,540.0,'auto',NULL,NULL,NULL,NULL);
INSERT INTO "decisions" VALUES(1,11,10,1641080400.0,'2022-01-01T23:40:00Z','mpc','',1,-4.13425077302198740658e+05,18.0,1,100.0,18.0,1,100.0,'verified','[]','[{"stage":"decide:mpc","set":{"phi_deg":18.0,"afr":1,"or_pct":100.0},"why":"candidates: 11 louver positions x 6 damper sets (regimes [1, 3, 5, 6, 9, 10]), OR grid [0.0, 100.0] % | stage 1: screened 121 candidates at 300 s steps | stage 2: 13 at full resolution (10 finalists, OR brackets of 1 pairs), best louver +18 deg, regime 1, OR 100.0 %, J -114.84 Wh | stage 3: not needed (the best''s louver neighbours were evaluated)"},{"stage":"wind","set":{},"why":"wind 4.5 m/s below 15 m/s"},{"stage":"hold","set":{},"why":"no manual hold"},{"stage":"faults","set":{},"why":"no fault"},{"stage":"limits","set":{},"why":"louver -90..90 deg, dampers 0..100 %"},{"stage":"quantisation","set":{},"why":"louver onto the 18 deg motor grid, dampers onto 1 % steps"},{"stage":"rate","set":{},"why":"within rate limits"},{"stage":"regimes","set":{},"why":"regime 1 available"},{"stage":"occupancy","set":{"occupied":false,"source":"schedule"},"why":"unoccupied: no occupancy schedule"},{"stage":"comfort","set":{},"why":"unoccupied (no limit); direct sun 95 W/m2, DGPs 1.00, supply air 27.9 \u00b0C, asymmetry +4.0 K"}]','{"read":18.107,"quality":0.044,"estimate":2.56,"calibrate":0.017,"decide":24.832,"safety":0.152,"write":0.139,"predict":2.715,"comfort":0.618}',4.91840000000000046034e+01,0,NULL,NULL,NULL,600.0,'auto',NULL,NULL,NULL,NULL);
INSERT INTO "decisions" VALUES(1,12,11,1641080460.0,'2022-01-01T23:41:00Z','mpc','',1,-4.07359120276579866198e+05,18.0,1,100.0,18.0,1,100.0,'verified','[]','[{"stage":"decide:mpc","set":{"phi_deg":18.0,"afr":1,"or_pct":100.0},"why":"candidates: 11 louver positions x 6 damper sets (regimes [1, 3, 5, 6, 9, 10]), OR grid [0.0, 100.0] % | stage 1: screened 121 candidates at 300 s steps | stage 2: 12 at full resolution (10 finalists, OR brackets of 1 pairs), best louver +18 deg, regime 1, OR 100.0 %, J -113.16 Wh | stage 3: not needed (the best''s louver neighbours were evaluated)"},{"stage":"wind","set":{},"why":"wind 4.3 m/s below 15 m/s"},{"stage":"hold","set":{},"why":"no manual hold"},{"stage":"faults","set":{},"why":"no fault"},{"stage":"limits","set":{},"why":"louver -90..90 deg, dampers 0..100 %"},{"stage":"quantisation","set":{},"why":"louver onto the 18 deg motor grid, dampers onto 1 % steps"},{"stage":"rate","set":{},"why":"within rate limits"},{"stage":"regimes","set":{},"why":"regime 1 available"},{"stage":"occupancy","set":{"occupied":false,"source":"schedule"},"why":"unoccupied: no occupancy schedule"},{"stage":"comfort","set":{},"why":"unoccupied (no limit); direct sun 95 W/m2, DGPs 1.00, supply air 27.4 \u00b0C, asymmetry +3.8 K"}]','{"read":9.724,"quality":0.041,"estimate":2.262,"calibrate":0.016,"decide":28.806,"safety":0.124,"write":0.141,"predict":2.852,"comfort":0.718}',44.684,0,NULL,NULL,NULL,660.0,'auto',NULL,NULL,NULL,NULL);
INSERT INTO "decisions" VALUES(1,13,12,1641080520.0,'2022-01-01T23:42:00Z','mpc','',1,-4.64498775327663694038e+05,18.0,1,100.0,18.0,1,100.0,'verified','[]','[{"stage":"decide:mpc","set":{"phi_deg":18.0,"afr":1,"or_pct":100.0},"why":"candidates: 11 louver positions x 6 damper sets (regimes [1, 3, 5, 6, 9, 10]), OR grid [0.0, 100.0] % | stage 1: screened 121 candidates at 300 s steps | stage 2: 11 at full resolution (10 finalists, OR brackets of 1 pairs), best louver +18 deg, regime 1, OR 100.0 %, J -129.03 Wh | stage 3: not needed (the best''s louver neighbours were evaluated)"},{"stage":"wind","set":{},"why":"wind 4.2 m/s below 15 m/s"},{"stage":"hold","set":{},"why":"no manual hold"},{"stage":"faults","set":{},"why":"no fault"},{"stage":"limits","set":{},"why":"louver -90..90 deg, dampers 0..100 %"},{"stage":"quantisation","set":{},"why":"louver onto the 18 deg motor grid, dampers onto 1 % steps"},{"stage":"rate","set":{},"why":"within rate limits"},{"stage":"regimes","set":{},"why":"regime 1 available"},{"stage":"occupancy","set":{"occupied":false,"source":"schedule"},"why":"unoccupied: no occupancy schedule"},{"stage":"comfort","set":{},"why":"unoccupied (no limit); direct sun 97 W/m2, DGPs 1.00, supply air 27.2 \u00b0C, asymmetry +3.7 K"}]','{"read":2.997,"quality":0.038,"estimate":2.347,"calibrate":294.4,"decide":25.435,"safety":0.092,"write":0.12,"predict":2.66,"comfort":0.527}',328.616,0,NULL,NULL,NULL,720.0,'auto',NULL,NULL,NULL,NULL);
INSERT INTO "decisions" VALUES(1,14,13,1641080580.0,'2022-01-01T23:43:00Z','mpc','',1,-4.76142735281772736932e+05,18.0,1,100.0,18.0,1,100.0,'verified','[]','[{"stage":"decide:mpc","set":{"phi_deg":18.0,"afr":1,"or_pct":100.0},"why":"candidates: 11 louver positions x 6 damper sets (regimes [1, 3, 5, 6, 9, 10]), OR grid [0.0, 100.0] % | stage 1: screened 121 candidates at 300 s steps | stage 2: 11 at full resolution (10 finalists, OR brackets of 1 pairs), best louver +18 deg, regime 1, OR 100.0 %, J -132.26 Wh | stage 3: not needed (the best''s louver neighbours were evaluated)"},{"stage":"wind","set":{},"why":"wind 4.1 m/s below 15 m/s"},{"stage":"hold","set":{},"why":"no manual hold"},{"stage":"faults","set":{},"why":"no fault"},{"stage":"limits","set":{},"why":"louver -90..90 deg, dampers 0..100 %"},{"stage":"quantisation","set":{},"why":"louver onto the 18 deg motor grid, dampers onto 1 % steps"},{"stage":"rate","set":{},"why":"within rate limits"},{"stage":"regimes","set":{},"why":"regime 1 available"},{"stage":"occupancy","set":{"occupied":false,"source":"schedule"},"why":"unoccupied: no occupancy schedule"},{"stage":"comfort","set":{},"why":"unoccupied (no limit); direct sun 97 W/m2, DGPs 1.00, supply air 26.9 \u00b0C, asymmetry +4.0 K"}]','{"read":7.662,"quality":0.058,"estimate":2.46,"calibrate":0.017,"decide":29.615,"safety":0.096,"write":0.117,"predict":2.588,"comfort":0.627}',4.32399999999999948849e+01,0,NULL,NULL,NULL,780.0,'auto',NULL,NULL,NULL,NULL);
INSERT INTO "decisions" VALUES(1,15,14,1641080640.0,'2022-01-01T23:44:00Z','mpc','',1,-4.71517313336308230634e+05,18.0,1,100.0,18.0,1,100.0,'verified','[]','[{"stage":"decide:mpc","set":{"phi_deg":18.0,"afr":1,"or_pct":100.0},"why":"candidates: 11 louver positions x 6 damper sets (regimes [1, 3, 5, 6, 9, 10]), OR grid [0.0, 100.0] % | stage 1: screened 121 candidates at 300 s steps | stage 2: 11 at full resolution (10 finalists, OR brackets of 1 pairs), best louver +18 deg, regime 1, OR 100.0 %, J -130.98 Wh | stage 3: not needed (the best''s louver neighbours were evaluated)"},{"stage":"wind","set":{},"why":"wind 3.9 m/s below 15 m/s"},{"stage":"hold","set":{},"why":"no manual hold"},{"stage":"faults","set":{},"why":"no fault"},{"stage":"limits","set":{},"why":"louver -90..90 deg, dampers 0..100 %"},{"stage":"quantisation","set":{},"why":"louver onto the 18 deg motor grid, dampers onto 1 % steps"},{"stage":"rate","set":{},"why":"within rate limits"},{"stage":"regimes","set":{},"why":"regime 1 available"},{"stage":"occupancy","set":{"occupied":false,"source":"schedule"},"why":"unoccupied: no occupancy schedule"},{"stage":"comfort","set":{},"why":"unoccupied (no limit); direct sun 97 W/m2, DGPs 1.00, supply air 27.0 \u00b0C, asymmetry +3.8 K"}]','{"read":2.296,"quality":0.044,"estimate":2.194,"calibrate":0.014,"decide":22.224,"safety":0.109,"write":0.123,"predict":2.729,"comfort":0.528}',30.261,0,NULL,NULL,NULL,840.0,'auto',NULL,NULL,NULL,NULL);
INSERT INTO "decisions" VALUES(1,16,15,1641080700.0,'2022-01-01T23:45:00Z','mpc','',1,-4.66942537871192092993e+05,18.0,1,100.0,18.0,1,100.0,'verified','[]','[{"stage":"decide:mpc","set":{"phi_deg":18.0,"afr":1,"or_pct":100.0},"why":"candidates: 11 louver positions x 6 damper sets (regimes [1, 3, 5, 6, 9, 10]), OR grid [0.0, 100.0] % | stage 1: screened 121 candidates at 300 s steps | stage 2: 11 at full resolution (10 finalists, OR brackets of 1 pairs), best louver +18 deg, regime 1, OR 100.0 %, J -129.71 Wh | stage 3: not needed (the best''s louver neighbours were evaluated)"},{"stage":"wind","set":{},"why":"wind 3.6 m/s below 15 m/s"},{"stage":"hold","set":{},"why":"no manual hold"},{"stage":"faults","set":{},"why":"no fault"},{"stage":"limits","set":{},"why":"louver -90..90 deg, dampers 0..100 %"},{"stage":"quantisation","set":{},"why":"louver onto the 18 deg motor grid, dampers onto 1 % steps"},{"stage":"rate","set":{},"why":"within rate limits"},{"stage":"regimes","set":{},"why":"regime 1 available"},{"stage":"occupancy","set":{"occupied":false,"source":"schedule"},"why":"unoccupied: no occupancy schedule"},{"stage":"comfort","set":{},"why":"unoccupied (no limit); direct sun 97 W/m2, DGPs 1.00, supply air 26.9 \u00b0C, asymmetry +3.8 K"}]','{"read":2.07,"quality":0.046,"estimate":2.146,"calibrate":0.013,"decide":15.151,"safety":0.098,"write":0.122,"predict":2.555,"comfort":0.557}',2.27579999999999955657e+01,0,NULL,NULL,NULL,900.0,'auto',NULL,NULL,NULL,NULL);
INSERT INTO "decisions" VALUES(1,17,16,1641080760.0,'2022-01-01T23:46:00Z','mpc','',1,-4.82548193027032888474e+05,18.0,1,100.0,18.0,1,100.0,'verified','[]','[{"stage":"decide:mpc","set":{"phi_deg":18.0,"afr":1,"or_pct":100.0},"why":"candidates: 11 louver positions x 6 damper sets (regimes [1, 3, 5, 6, 9, 10]), OR grid [0.0, 100.0] % | stage 1: screened 121 candidates at 300 s steps | stage 2: 11 at full resolution (10 finalists, OR brackets of 1 pairs), best louver +18 deg, regime 1, OR 100.0 %, J -134.04 Wh | stage 3: not needed (the best''s louver neighbours were evaluated)"},{"stage":"wind","set":{},"why":"wind 3.6 m/s below 15 m/s"},{"stage":"hold","set":{},"why":"no manual hold"},{"stage":"faults","set":{},"why":"no fault"},{"stage":"limits","set":{},"why":"louver -90..90 deg, dampers 0..100 %"},{"stage":"quantisation","set":{},"why":"louver onto the 18 deg motor grid, dampers onto 1 % steps"},{"stage":"rate","set":{},"why":"within rate limits"},{"stage":"regimes","set":{},"why":"regime 1 available"},{"stage":"occupancy","set":{"occupied":false,"source":"schedule"},"why":"unoccupied: no occupancy schedule"},{"stage":"comfort","set":{},"why":"unoccupied (no limit); direct sun 102 W/m2, DGPs 1.00, supply air 26.5 \u00b0C, asymmetry +4.1 K"}]','{"read":2.224,"quality":0.044,"estimate":2.34,"calibrate":0.014,"decide":15.048,"safety":0.096,"write":0.122,"predict":2.633,"comfort":0.527}',2.30480000000000018189e+01,0,NULL,NULL,NULL,960.0,'auto',NULL,NULL,NULL,NULL);
INSERT INTO "decisions" VALUES(1,18,17,1641080820.0,'2022-01-01T23:47:00Z','mpc','',1,-480590.130141915,18.0,1,100.0,18.0,1,100.0,'verified','[]','[{"stage":"decide:mpc","set":{"phi_deg":18.0,"afr":1,"or_pct":100.0},"why":"candidates: 11 louver positions x 6 damper sets (regimes [1, 3, 5, 6, 9, 10]), OR grid [0.0, 100.0] % | stage 1: screened 121 candidates at 300 s steps | stage 2: 12 at full resolution (10 finalists, OR brackets of 1 pairs), best louver +18 deg, regime 1, OR 100.0 %, J -133.50 Wh | stage 3: not needed (the best''s louver neighbours were evaluated)"},{"stage":"wind","set":{},"why":"wind 2.9 m/s below 15 m/s"},{"stage":"hold","set":{},"why":"no manual hold"},{"stage":"faults","set":{},"why":"no fault"},{"stage":"limits","set":{},"why":"louver -90..90 deg, dampers 0..100 %"},{"stage":"quantisation","set":{},"why":"louver onto the 18 deg motor grid, dampers onto 1 % steps"},{"stage":"rate","set":{},"why":"within rate limits"},{"stage":"regimes","set":{},"why":"regime 1 available"},{"stage":"occupancy","set":{"occupied":false,"source":"schedule"},"why":"unoccupied: no occupancy schedule"},{"stage":"comfort","set":{},"why":"unoccupied (no limit); direct sun 100 W/m2, DGPs 1.00, supply air 25.6 \u00b0C, asymmetry +3.9 K"}]','{"read":2.137,"quality":0.043,"estimate":2.064,"calibrate":346.991,"decide":20.884,"safety":0.094,"write":0.118,"predict":2.712,"comfort":0.523}',3.75566000000000030931e+02,0,NULL,NULL,NULL,1020.0,'auto',NULL,NULL,NULL,NULL);
INSERT INTO "decisions" VALUES(1,19,18,1641080880.0,'2022-01-01T23:48:00Z','mpc','',1,-4.81689515671184752135e+05,18.0,1,100.0,18.0,1,100.0,'verified','[]','[{"stage":"decide:mpc","set":{"phi_deg":18.0,"afr":1,"or_pct":100.0},"why":"candidates: 11 louver positions x 6 damper sets (regimes [1, 3, 5, 6, 9, 10]), OR grid [0.0, 100.0] % | stage 1: screened 121 candidates at 300 s steps | stage 2: 12 at full resolution (10 finalists, OR brackets of 1 pairs), best louver +18 deg, regime 1, OR 100.0 %, J -133.80 Wh | stage 3: not needed (the best''s louver neighbours were evaluated)"},{"stage":"wind","set":{},"why":"wind 2.8 m/s below 15 m/s"},{"stage":"hold","set":{},"why":"no manual hold"},{"stage":"faults","set":{},"why":"no fault"},{"stage":"limits","set":{},"why":"louver -90..90 deg, dampers 0..100 %"},{"stage":"quantisation","set":{},"why":"louver onto the 18 deg motor grid, dampers onto 1 % steps"},{"stage":"rate","set":{},"why":"within rate limits"},{"stage":"regimes","set":{},"why":"regime 1 available"},{"stage":"occupancy","set":{"occupied":false,"source":"schedule"},"why":"unoccupied: no occupancy schedule"},{"stage":"comfort","set":{},"why":"unoccupied (no limit); direct sun 102 W/m2, DGPs 1.00, supply air 26.3 \u00b0C, asymmetry +3.8 K"}]','{"read":4.128,"quality":0.047,"estimate":2.344,"calibrate":0.015,"decide":21.732,"safety":0.094,"write":0.112,"predict":2.727,"comfort":0.56}',3.17589999999999967879e+01,0,NULL,NULL,NULL,1080.0,'auto',NULL,NULL,NULL,NULL);
INSERT INTO "decisions" VALUES(1,20,19,1641080940.0,'2022-01-01T23:49:00Z','mpc','',1,-4.81782591240803303653e+05,18.0,1,100.0,18.0,1,100.0,'verified','[]','[{"stage":"decide:mpc","set":{"phi_deg":18.0,"afr":1,"or_pct":100.0},"why":"candidates: 11 louver positions x 6 damper sets (regimes [1, 3, 5, 6, 9, 10]), OR grid [0.0, 100.0] % | stage 1: screened 121 candidates at 300 s steps | stage 2: 13 at full resolution (10 finalists, OR brackets of 1 pairs), best louver +18 deg, regime 1, OR 100.0 %, J -133.83 Wh | stage 3: not needed (the best''s louver neighbours were evaluated)"},{"stage":"wind","set":{},"why":"wind 2.5 m/s below 15 m/s"},{"stage":"hold","set":{},"why":"no manual hold"},{"stage":"faults","set":{},"why":"no fault"},{"stage":"limits","set":{},"why":"louver -90..90 deg, dampers 0..100 %"},{"stage":"quantisation","set":{},"why":"louver onto the 18 deg motor grid, dampers onto 1 % steps"},{"stage":"rate","set":{},"why":"within rate limits"},{"stage":"regimes","set":{},"why":"regime 1 available"},{"stage":"occupancy","set":{"occupied":false,"source":"schedule"},"why":"unoccupied: no occupancy schedule"},{"stage":"comfort","set":{},"why":"unoccupied (no limit); direct sun 104 W/m2, DGPs 1.00, supply air 26.0 \u00b0C, asymmetry +3.8 K"}]','{"read":7.205,"quality":0.046,"estimate":2.326,"calibrate":0.014,"decide":20.178,"safety":0.09,"write":0.113,"predict":2.389,"comfort":0.597}',32.958,0,NULL,NULL,NULL,1140.0,'auto',NULL,NULL,NULL,NULL);
CREATE TABLE events (
    event_id INTEGER PRIMARY KEY AUTOINCREMENT,
    run_id INTEGER NOT NULL REFERENCES runs(run_id),
    cycle INTEGER NOT NULL,
    time_s REAL NOT NULL,
    level TEXT NOT NULL,
    kind TEXT NOT NULL,
    message TEXT NOT NULL
);
CREATE TABLE findings (
    finding_id INTEGER PRIMARY KEY AUTOINCREMENT,
    run_id INTEGER,
    kind TEXT NOT NULL,
    subject TEXT NOT NULL DEFAULT '',
    confidence REAL NOT NULL,
    start_s REAL NOT NULL,
    detected_s REAL NOT NULL,
    opened_s REAL NOT NULL,
    last_seen_s REAL NOT NULL,
    evidence TEXT NOT NULL DEFAULT '[]',
    action TEXT NOT NULL,
    state TEXT NOT NULL DEFAULT 'open',
    ended_s REAL,
    end_reason TEXT NOT NULL DEFAULT '',
    ack_command_id INTEGER
);
CREATE TABLE meta (
    key TEXT PRIMARY KEY,
    value TEXT NOT NULL
);
INSERT INTO "meta" VALUES('schema_version','7');
INSERT INTO "meta" VALUES('created_utc','2026-11-28T03:44:22Z');
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
INSERT INTO "model" VALUES(1,1,1641079800.0,9.09301817362228348429e+00,4.65189099818475710907e+01,2.87633601868460573322e+01,4.97162004208274765915e+01,4.35209528188196941283e+01,3.76411350843468426327e+01,NULL,NULL,NULL,NULL,NULL,NULL,NULL,NULL,NULL,NULL,300.0,9.92071277588223665588e+00,4.4694321286495835464e+01,2.93807943175600030363e+01,4.14604657926635695747e+01,2.77074386984355101057e+01,18.0,1,100.0,0.0,0.0,0.0,0.0);
INSERT INTO "model" VALUES(1,2,1641079860.0,8.8325666889736,46.1729806361256,2.87523796623081580037e+01,4.64931651947289878998e+01,3.02033166887960078392e+01,3.74626801492169079219e+01,9.32684054518637140063e+00,4.62309845831630354933e+01,2.89048007625033278591e+01,4.72401941979771891047e+01,2.89517268195549490892e+01,1.11278786069980595296e-01,2.70146737390808596053e+02,4.23791500949909732314e+02,1.02343358884382621451e+03,120.0,300.0,9.67459260711416391131e+00,4.41647804531141900934e+01,2.93387784901726718089e+01,4.01536033012256439195e+01,2.79994957191128150957e+01,18.0,1,100.0,1.82006854832403296316e+04,2.3198410476671575452e+04,6.73098022939154616312e+04,7200.0);
INSERT INTO "model" VALUES(1,3,1641079920.0,8.87887905513190389683e+00,4.58924091224853896147e+01,2.87591549200661802379e+01,4.45597320043699483002e+01,2.93721836015074018177e+01,3.73257820212758133497e+01,9.06663947526954,4.58061029805767816469e+01,2.89055462339312043687e+01,4.43647822267839728746e+01,2.90816345400685918312e+01,1.06289604338606874511e-01,2.60296076262289716391e+02,4.45475289134976264919e+02,7.24232844923118250328e+02,120.0,300.0,9.74110301944392631412e+00,4.38721388043452407154e+01,2.9401087844821006457e+01,4.00224712202954719959e+01,2.73389059428201335326e+01,18.0,7,100.0,3.64475942830620188036e+04,4.70338786086392647133e+04,1.17386825331571802957e+05,1.43999999999999963619e+04);
INSERT INTO "model" VALUES(1,4,1641079980.0,8.51666301602745,4.55066120471283284141e+01,28.9114501103694,4.1443504394474075525e+01,2.46150656551712359036e+01,3.72090310787488647297e+01,9.07334913037829,4.54681871117803098041e+01,28.9087176554645,4.2885861021627874833e+01,2.58914107171219711736e+01,3.92727072785192532489e-02,2.6363176993827278239e+02,4.56828335564326494001e+02,8.54659646565941102415e+02,120.0,300.0,9.36260301524703208997e+00,4.32151643018714821681e+01,29.489938990393,3.76806723190550201256e+01,2.48540374267343509026e+01,18.0,7,100.0,5.47398683501108826009e+04,7.13691226737152319397e+04,1.87134887726059299896e+05,2.15999999999999963621e+04);
INSERT INTO "model" VALUES(1,5,1641080040.0,8.41987720805809658486e+00,4.50991151491652431104e+01,2.89319773950859371325e+01,3.99193964120273676599e+01,2.42248146362812804004e+01,3.70155462721255617002e+01,8.70552456657378570525e+00,4.49983291039504251784e+01,2.90473713680660807759e+01,39.6393083025946,2.36585118270868974841e+01,4.12379134981020328831e-02,2.69222426847801045825e+02,4.56718341467515074336e+02,8.28219391426557649538e+02,120.0,300.0,9.21231405917228585167e+00,4.26599226830812199278e+01,2.94743575400902955161e+01,3.627325987921807382e+01,2.31926098440710575236e+01,18.0,7,100.0,7.30744197052460222035e+04,9.62099531682513188588e+04,2.51195222613091871601e+05,2.87999999999999963624e+04);
INSERT INTO "model" VALUES(1,6,1641080100.0,8.40013334146459555995e+00,4.46243875400882643571e+01,2.90127763168973160654e+01,3.8851078189035035848e+01,2.57934500648898961121e+01,3.68185819284927902113e+01,8.67142125911419725525e+00,4.45880003225167342861e+01,2.90781889972777776156e+01,3.8406704575357707653e+01,2.3498050348156596101e+01,4.02903600199658942782e-02,2.59799734994039795317e+02,4.77436687472067831103e+02,778.365035817123,120.0,300.0,9.44461222165688241148e+00,4.22893352578080907724e+01,2.95882088404071623699e+01,3.59315045453931816146e+01,2.38621072388363018043e+01,18.0,7,100.0,9.14466376691789337161e+04,1.21533463538899944977e+05,2.98008598869362671401e+05,36000.0);
INSERT INTO "model" VALUES(1,7,1641080160.0,8.33916219777415790304e+00,4.41661715835846848668e+01,2.90342350266735138575e+01,3.80311262815386612601e+01,2.56865048739799135542e+01,3.66002033051290709408e+01,8.66073168799272252726e+00,4.41554566553057838964e+01,2.91391167243442055223e+01,3.78545454445060158832e+01,2.60138039743622471186e+01,3.05477906599491248751e-02,2.77211213609742742388e+02,489.134421294002,5.97385029839640651532e+02,120.0,300.0,9.45696359647394,4.21148936237393058936e+01,29.5411532705578,3.65070044141779135324e+01,2.59056087968367592115e+01,18.0,7,100.0,1.09851780587039946112e+05,1.47332794451166293578e+05,3.41112120660753280389e+05,43200.0);
INSERT INTO "model" VALUES(1,8,1641080220.0,8.14924582269009,4.38191112898971368849e+01,2.90127257663842215151e+01,3.8008479193376956573e+01,2.61346475853392234967e+01,3.64159185281406507775e+01,8.63344236795705910481e+00,4.37128198637374794106e+01,2.91650066916030255015e+01,3.70227045473470752759e+01,2.6116926901579176957e+01,2.86010871558203295939e-02,2.70242321878486904999e+02,5.0192766706610609617e+02,5.4700407419503414984e+02,120.0,300.0,9.47260879718754722489e+00,4.18903196482269777342e+01,2.95600484939489547295e+01,3.653772567112099523e+01,2.61324232306452586271e+01,18.0,7,100.0,1.28285581122290401258e+05,1.73611975125850120094e+05,3.7915879366332554492e+05,50400.0);
INSERT INTO "model" VALUES(1,9,1641080280.0,8.10215258795335557806e+00,4.3482964531053653447e+01,2.90389146936457791525e+01,37.7724450456281,2.68716411275140671928e+01,3.62609396123497162989e+01,8.45355721708693863547e+00,4.34004329746903181339e+01,2.91326220307112180316e+01,3.71180414098059259227e+01,2.72030459800194535091e+01,2.38792792665054390277e-02,2.78813452794422687473e+02,5.07014637022844624411e+02,4.58431302350460327926e+02,120.0,300.0,9.41815670908289348517e+00,4.17233483579105950394e+01,2.95312120678887595204e+01,3.7614766094227320536e+01,2.75157714785648295214e+01,18.0,1,100.0,1.46744480798802484061e+05,2.00375009982127259724e+05,412562.615095209,57600.0);
INSERT INTO "model" VALUES(1,10,1641080340.0,8.17754698488812437062e+00,4.31799672995374521616e+01,29.006384231401,3.65642458533567946696e+01,1.1021155809739980214e+01,3.6093175765469254657e+01,8.43436237354041,4.30828857247859673415e+01,2.91546995153678949463e+01,3.76466749177461110784e+01,2.75302614042840332331e+01,0.0933704320509684,2.80870359221952639924e+02,5.15297418132407869951e+02,4.57562015428890049399e+02,120.0,300.0,9.51097168888367150429e+00,4.13660604963272362502e+01,2.94911502323142258328e+01,3.65576375230834287326e+01,2.61976567033092919709e+01,18.0,1,100.0,1.65225707357602834236e+05,2.27625878276769391954e+05,4.15494244322739075857e+05,64800.0);
INSERT INTO "model" VALUES(1,11,1641080400.0,8.28035954667439,4.2795291221012519145e+01,2.9040714183218369726e+01,3.66399491507928587452e+01,2.79245653319877646931e+01,3.59180027021154728576e+01,8.4547951655464430587e+00,4.27258197444772918043e+01,2.91249679111198815917e+01,3.5777174508278164922e+01,2.6078353636951021599e+01,9.00461133235035404709e-02,2.76594263850206743891e+02,5.24574991610310917148e+02,2.07348388597996915907e+02,120.0,300.0,9.59043454170671338943e+00,41.159285923705,2.95281229648022645059e+01,36.6558947135797,2.68046774872078685802e+01,18.0,1,100.0,183725.28938495,2.55272100784634938474e+05,4.30556967654705047623e+05,72000.0);
INSERT INTO "model" VALUES(1,12,1641080460.0,8.22404028112225660152e+00,42.506477264642,2.90004734939084869438e+01,3.69057832387687199124e+01,2.74009600719432455662e+01,3.57534753792752439953e+01,8.58417588869286873887e+00,4.24175554551737832298e+01,2.91614900508001824164e+01,3.62545235563758296839e+01,2.68730251211679274083e+01,9.02427530010499745483e-02,2.69712131783095173894e+02,527.56858966406,4.23124211270041882936e+02,120.0,300.0,9.53568278235565,4.0959407292447963301e+01,2.95200813957687842048e+01,3.6589048791417440043e+01,2.71734177938118932611e+01,18.0,1,100.0,2.02238671452752663743e+05,2.83279463220159057534e+05,4.58738043651675339801e+05,79200.0);
INSERT INTO "model" VALUES(1,13,1641080520.0,8.40585628504953774609e+00,4.21912902093626485111e+01,2.89101051108374349505e+01,37.0004389019565,2.72297672806677724119e+01,3.55506976601000133095e+01,8.54189059456302857142e+00,42.1518838829619,2.91288259669091189598e+01,3.63449863022709109819e+01,2.7254210449203071676e+01,8.96234792111084282995e-02,2.60908119143773035378e+02,5.35517335517752940182e+02,406.368276769949,120.0,300.0,8.4960310512009868944e+00,4.08862699615695532892e+01,2.91625093505011250272e+01,3.45501345419081076206e+01,2.66279332699936617241e+01,18.0,1,100.0,2.2076267053572664735e+05,3.11651071410425123766e+05,4.8731782527308317365e+05,86400.0);
INSERT INTO "model" VALUES(1,14,1641080580.0,8.27978517020255821989e+00,4.19658723940477784708e+01,2.89369051654837221576e+01,3.72381476512352946892e+01,2.68750894789031917757e+01,3.54513887797657503133e+01,8.44277526813971235242e+00,4.19078987969563172572e+01,2.8950367745350831683e+01,3.54927884062402085882e+01,2.65343471423832966138e+01,1.48049603121389899973e-01,2.83464115969669705908e+02,5.36411018931410353604e+02,6.81140117235699108291e+02,120.0,300.0,8.49103281884237,4.0672191670833115042e+01,2.90984617747685661006e+01,3.45319390554772098766e+01,2.65350840928373372658e+01,18.0,1,100.0,2.39294886255638295543e+05,3.40389952743728354113e+05,5.16070645328664220864e+05,93600.0);
INSERT INTO "model" VALUES(1,15,1641080640.0,8.39600811720623596556e+00,4.17315800404328456334e+01,2.88528774748019714016e+01,3.74301633612038244782e+01,2.69843948683786720725e+01,3.52922287576174085197e+01,8.34273958625755,4.17004428591888540731e+01,2.89809025510922424473e+01,3.59269241595246739966e+01,2.69947300891237205186e+01,1.47430950297189139464e-01,2.77691312959198910448e+02,5.39824067231367621388e+02,6.65662356672868668269e+02,120.0,300.0,8.60882286793423645576e+00,4.05105391053455718983e+01,29.0563982529481,3.48719178012656243485e+01,2.69676563931626560592e+01,18.0,1,100.0,2.5783354869664786384e+05,3.69499060268481378452e+05,5.4484532324591442012e+05,100800.0);
INSERT INTO "model" VALUES(1,16,1641080700.0,8.15652570340626,4.15159686838703692038e+01,2.88735171582775933529e+01,37.0164099936751,2.68636949435999667907e+01,3.51947429210739528562e+01,8.43272285032532,4.14805393823229451299e+01,2.88986399480230033987e+01,3.63262717514029418461e+01,2.73095437282803459315e+01,1.47590546903685365665e-01,2.74094180787615300694e+02,540.601826162688,6.70731362312108672077e+02,120.0,300.0,8.40896845661450242914e+00,4.03127315593802677557e+01,2.90631075161186345221e+01,3.47970503419176679926e+01,2.71666358380859946915e+01,18.0,1,100.0,2.76377600460440502505e+05,399004.168935386,5.7354047730945551301e+05,108000.0);
INSERT INTO "model" VALUES(1,17,1641080760.0,8.39075974778774,4.12392549604535361149e+01,2.89458211626090928803e+01,3.65497795387848327668e+01,2.65428718425112037944e+01,3.5092538061531286075e+01,8.21418396250311388939e+00,4.12716429232538644083e+01,2.89097788122011820641e+01,3.60795566922237753715e+01,2.71708559934461959519e+01,1.48048556558231597657e-01,2.90283502837695380101e+02,5.64636862199226129653e+02,6.80440235392114573182e+02,120.0,300.0,8.52423065968173432338e+00,4.00874959531704462296e+01,2.90798910712219367269e+01,3.45866848288500250419e+01,2.70834552142872553304e+01,18.0,1,100.0,2.94926684374921896959e+05,4.28917731765680946415e+05,6.02091058323814766473e+05,115200.0);
INSERT INTO "model" VALUES(1,18,1641080820.0,8.12222394279132231531e+00,4.10095875046247897426e+01,2.88535451322337053179e+01,3.64940406461196857894e+01,2.55915737607328424023e+01,3.49315663184292475302e+01,8.43140539920926812555e+00,4.09960974282977872471e+01,2.89775032117575506154e+01,3.57753267446721565656e+01,2.74790817265501345905e+01,1.46042461277894497495e-01,2.87257705186460611914e+02,5.55283408916561711538e+02,6.46088592740392869033e+02,120.0,300.0,8.25108974677238,3.99165378014739644649e+01,2.88936044841429406915e+01,3.47798460688593422682e+01,2.70479598107172023455e+01,18.0,1,100.0,3.13480892026656598309e+05,4.59243348056355782339e+05,6.3045653026190726087e+05,122400.0);
INSERT INTO "model" VALUES(1,19,1641080880.0,8.21853627431880795484e+00,4.09549756949426182464e+01,2.88058794188573870087e+01,3.68903141362753785861e+01,2.63086882490233051621e+01,3.48804275569000310497e+01,8.16396893537796586315e+00,4.07867102800323095852e+01,2.8872019895470486972e+01,3.59410921937446232727e+01,27.4484048110362,1.51153376203131434296e-01,2.8184593187418204253e+02,5.65251026994414928605e+02,640.395962236077,120.0,300.0,8.36477504357435464044e+00,3.99276312991615327518e+01,2.88993744746707079693e+01,3.5280711851855471651e+01,2.73380559636317457252e+01,18.0,1,100.0,3.32040641008932143458e+05,4.89984548746501561268e+05,6.58612924469350720759e+05,129600.0);
INSERT INTO "model" VALUES(1,20,1641080940.0,8.32780395260624572983e+00,4.08943558421473767321e+01,2.88602418643507689921e+01,3.62235115015485575895e+01,2.59578572797414040005e+01,3.48772988532490444421e+01,8.29295213629336558369e+00,4.07482061355551650194e+01,2.8829561787220370661e+01,3.65719599298984689985e+01,2.76282208063793746069e+01,1.52188743780268864735e-01,2.80182768143598195827e+02,5.76339919681007131638e+02,6.66320395700522112754e+02,120.0,300.0,8.58709086297665180609e+00,3.98691277337181304574e+01,2.89545996325692271966e+01,3.51369415139824354805e+01,2.72883592868805067164e+01,18.0,1,100.0,3.50606635055526741785e+05,5.21144799247585935536e+05,6.86547738460877444597e+05,136800.0);
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
INSERT INTO "parameters" VALUES(1,1,1641079800.0,'prior',12.0,3.5,4.0,3.5,4.4,2.5,100.0,0.05,0.6,'{"q_x1":0.0,"q_x2":0.0,"q_x3":0.0,"q_x4":0.0}',NULL,'no calibration state at /tmp/s7/state/calibration.json: starting from the panel priors');
INSERT INTO "parameters" VALUES(1,13,1641080520.0,'online',1.64848411402023096172e+01,2.44683675309490178406e+00,5.26221124683421859202e+00,3.24954337184761810064e+00,3.1547520409927627405e+00,2.80050769716367620176e+00,2.79900961578190141674e+01,0.0454862748883694,6.05694714162685166058e-01,'{"q_x1":-2.7203942822702607,"q_x2":4.146244441922784,"q_x3":-5.389924637253836,"q_x4":0.152369613225545}',1.78781038786723733835e+01,'88 residuals');
INSERT INTO "parameters" VALUES(1,18,1641080820.0,'online',1.70575576467459093525e+01,2.24769813258997919191e+00,5.27389537096894311929e+00,3.3623226015653329135e+00,2.89776320487048266727e+00,2.95307136925804636362e+00,2.48194698908167410422e+01,4.35553539271074097172e-02,6.07637505967337787637e-01,'{"q_x1":-3.269212034433158,"q_x2":5.946895457347638,"q_x3":-8.100707146689881,"q_x4":2.54959033638492}',84.6798348212377,'255 residuals');
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
INSERT INTO "runs" VALUES(1,'suwon-south','dry run, simulated plant, lumped','2026-11-28T03:44:22Z',16749,'0.1.0','/tmp/s7/panel.yaml','2026-11-28T03:44:24Z','cycles done',20,'{"panel":{"id":"suwon-south","description":"Paper test unit, 250 mm cavity, black PVC louver"},"site":{"latitude_deg":37.3,"longitude_deg":127.0,"elevation_m":40.0,"utc_offset_h":9.0,"albedo":0.2,"terrain":"city","facade_height_m":5.0},"facade":{"azimuth_deg":180.0,"width_m":2.0,"glazed_height_m":2.5,"cavity_depth_m":0.25},"glazing":{"exterior":{"thickness_m":0.006,"solar_transmittance":0.6,"solar_reflectance_front":0.17,"solar_reflectance_back":0.22,"visible_transmittance":0.84,"visible_reflectance_front":0.055,"visible_reflectance_back":0.078,"emissivity_front":0.84,"emissivity_back":0.1,"density_kgm3":2500.0,"heat_capacity_jkgk":840.0},"interior_outer":{"thickness_m":0.006,"solar_transmittance":0.775,"solar_reflectance_front":0.071,"solar_reflectance_back":0.071,"visible_transmittance":0.881,"visible_reflectance_front":0.08,"visible_reflectance_back":0.08,"emissivity_front":0.84,"emissivity_back":0.84,"density_kgm3":2500.0,"heat_capacity_jkgk":840.0},"interior_inner":{"thickness_m":0.006,"solar_transmittance":0.6,"solar_reflectance_front":0.22,"solar_reflectance_back":0.17,"visible_transmittance":0.84,"visible_reflectance_front":0.078,"visible_reflectance_back":0.055,"emissivity_front":0.1,"emissivity_back":0.84,"density_kgm3":2500.0,"heat_capacity_jkgk":840.0},"interior_gap_m":0.012},"louver":{"slat_width_m":0.05,"slat_pitch_m":0.045,"slat_thickness_m":0.0015,"solar_reflectance_upper":0.07,"solar_reflectance_lower":0.07,"visible_reflectance_upper":0.05,"visible_reflectance_lower":0.05,"emissivity":0.9,"density_kgm3":1400.0,"heat_capacity_jkgk":1000.0,"segments":5,"step_deg":18.0},"openings":{"exterior_bottom":{"area_m2":0.5,"discharge_coefficient":0.6},"exterior_top":{"area_m2":0.5,"discharge_coefficient":0.6},"interior_bottom":{"area_m2":0.5,"discharge_coefficient":0.6},"interior_top":{"area_m2":0.5,"discharge_coefficient":0.6},"stack_height_m":2.75,"min_opening_ratio":0.01,"room_pressure_pa":0.0,"regularisation_pa":0.01,"wind_pressure":{"incidence_deg":[0,15,30,45,60,75,90,105,120,135,150,165,180],"cp_bottom":[0.644,0.609,0.527,0.336,0.103,-0.245,-0.532,-0.617,-0.594,-0.445,-0.383,-0.314,-0.299],"cp_top":[0.794,0.721,0.585,0.363,0.077,-0.299,-0.637,-0.749,-0.691,-0.538,-0.46,-0.368,-0.363]}},"room":{"t_in_c":22.0,"t_mrt_c":null,"floor_depth_m":6.0},"daylight":{"luminous_efficacy_lmw":110.0,"utilisation":0.3,"lighting_power_wm2":10.0,"illuminance_setpoint_lx":500.0},"occupancy":null,"comfort":{"category":"B","direct_sun_max_wm2":5.0,"dgp_max":0.35,"supply_air_min_c":null,"supply_air_speed_ms":0.15,"turbulence_pct":40.0,"occupant_distance_m":1.0,"eye_height_m":1.2,"asymmetry_height_m":0.6,"sill_height_m":0.0},"model":{"step_s":60.0,"coupling":"implicit","ping_pong_substeps":1,"coupling_tolerance_k":1e-06,"coupling_max_iterations":40,"zoh":"eig","sky_model":"swinbank","q_air_basis":"ventilation_credit","decomposition":"erbs","transposition":"haydavies","louver_flow_loss":true,"cavity_air_profile":"exponential","cavity_air_probe":"mean","diagonal_flow":"power_law","louver_diffuse":"sky_ground","air_density_kgm3":1.19,"air_heat_capacity_jkgk":1006.0},"parameters":{"h_out":{"default":12.0,"lower":3.0,"upper":40.0},"h_ca1":{"default":3.5,"lower":1.0,"upper":15.0},"h_ca2":{"default":4.0,"lower":1.0,"upper":20.0},"h_ca3":{"default":3.5,"lower":1.0,"upper":15.0},"h_ca4":{"default":4.4,"lower":2.0,"upper":8.0},"h_in":{"default":2.5,"lower":1.0,"upper":8.0},"f":{"default":100.0,"lower":5.0,"upper":10000.0},"c":{"default":0.05,"lower":0.002,"upper":0.5},"n":{"default":0.6,"lower":0.5,"upper":1.0}},"calibration":{"window_h":1.0,"forgetting_factor":0.7,"horizon_steps":15,"start_stride_steps":4,"start_smoothing_s":480.0,"update_interval_s":300.0,"min_window_h":0.2,"max_nfev":3,"broyden_updates":1,"offline_max_nfev":40,"flow_from_velocity":true,"loss":"soft_l1","f_scale":1.0,"temperature_scale_k":0.3,"velocity_scale_ms":0.01,"adaptive_scales":true,"prior_weight":1.0,"identifiability_sd_ratio":1.0,"prior_log_sd":0.7,"prior_sd_n":0.15,"drift_log_sd_per_h":0.05,"heat_offsets":true,"offset_sd_wm2":20.0,"offset_bound_wm2":200.0,"offset_drift_wm2_per_h":20.0,"offset_tracking_s":600.0,"innovation_smoothing_s":[300.0,1800.0,1800.0,300.0],"reading_offset_tracking_s":[0.0,0.0,0.0,120.0,120.0],"reading_offset_memory_s":3600.0,"measurement_gain":[1.0,0.3,0.3,1.0,1.0],"spike_threshold_k":3.0,"fixed":[]},"control":{"mode":"auto","auto_heating_below_c":15.0,"horizon_steps":5,"optimiser":"mpc","or_grid_pct":[0.0,100.0],"or_refine_points":2,"or_refine_rounds":0,"flat_tolerance_pct":0.01,"refine_max_pairs":1,"screening_step_s":300.0,"screening_tolerance_k":0.1,"coupling_tolerance_k":0.0001,"full_candidates":8,"louver_neighbours":2,"finalist_margin_pct":20.0,"louver_move_penalty_wh":0.1,"time_budget_s":20.0,"baseline":{"sun_threshold_wm2":20.0,"night_angle_deg":90.0,"heating_open_above_room_k":2.0,"hysteresis_k":1.0,"cooling_flush_above_outdoor_k":1.0,"night_cooling_below_room_k":3.0}},"devices":null,"daemon":{"state_directory":null,"cycle_period_s":60.0,"calibrate_budget_s":10.0,"store_budget_s":5.0,"store_buffer_cycles":720,"room_temperature_source":"auto","max_predicted_cycles":1,"quality":{"stuck_window":15,"stuck_signals":["x1_c","x2_c","x3_c","x4_c","x5_c","t_out_c"],"max_rate_k_per_min":10.0,"rate_signals":["x1_c","x2_c","x3_c","t_room_c","t_out_c"],"max_sample_age_s":30.0},"metrics_file":null},"safety":{"safe_state":{"phi_deg":90.0,"afr":10,"or_pct":0.0},"fault_signals":["t_out_c","ghi_wm2"],"wind_limit_ms":15.0,"wind_hysteresis_ms":3.0,"wind_release_cycles":10,"wind_safe_angle_deg":90.0,"wind_close_exterior":true,"wind_unknown":"safe","phi_min_deg":-90.0,"phi_max_deg":90.0,"or_max_pct":100.0,"or_step_pct":1.0,"or_deadband_pct":5.0,"min_louver_move_interval_s":300.0,"manual_hold_min":120.0,"manual_reset_local":null},"mqtt":null,"bacnet":null}');
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
INSERT INTO "samples" VALUES(1,1,1641079800.0,'ghi_wm2',1.08508447168094733113e+02,'good','');
INSERT INTO "samples" VALUES(1,1,1641079800.0,'t_out_c',-3.96427537027044141204e-01,'good','');
INSERT INTO "samples" VALUES(1,1,1641079800.0,'t_room_c',2.16087486344909471833e+01,'good','');
INSERT INTO "samples" VALUES(1,1,1641079800.0,'v_cav_ms',1.85659242589108347543e-02,'good','');
INSERT INTO "samples" VALUES(1,1,1641079800.0,'wind_dir_deg',2.5851922339176570632e+02,'good','');
INSERT INTO "samples" VALUES(1,1,1641079800.0,'wind_speed_ms',5.6620992883441125798e+00,'good','');
INSERT INTO "samples" VALUES(1,1,1641079800.0,'x1_c',9.09301817362226572072e+00,'good','');
INSERT INTO "samples" VALUES(1,1,1641079800.0,'x2_c',4.6518909981847549771e+01,'good','');
INSERT INTO "samples" VALUES(1,1,1641079800.0,'x3_c',2.87633601868460786477e+01,'good','');
INSERT INTO "samples" VALUES(1,1,1641079800.0,'x4_c',4.9716200420827448168e+01,'good','');
INSERT INTO "samples" VALUES(1,1,1641079800.0,'x5_c',4.35209528188196941283e+01,'good','');
INSERT INTO "samples" VALUES(1,2,1641079860.0,'ghi_wm2',1.09694675717106463256e+02,'good','');
INSERT INTO "samples" VALUES(1,2,1641079860.0,'t_out_c',-2.79075557584899547336e-01,'good','');
INSERT INTO "samples" VALUES(1,2,1641079860.0,'t_room_c',2.16899832442396949265e+01,'good','');
INSERT INTO "samples" VALUES(1,2,1641079860.0,'v_cav_ms',1.9577718297493951205e-01,'good','');
INSERT INTO "samples" VALUES(1,2,1641079860.0,'wind_dir_deg',2.56134448852534717393e+02,'good','');
INSERT INTO "samples" VALUES(1,2,1641079860.0,'wind_speed_ms',5.14465973875842763618e+00,'good','');
INSERT INTO "samples" VALUES(1,2,1641079860.0,'x1_c',8.83256668897358387937e+00,'good','');
INSERT INTO "samples" VALUES(1,2,1641079860.0,'x2_c',4.60376380930381827721e+01,'good','');
INSERT INTO "samples" VALUES(1,2,1641079860.0,'x3_c',2.83967304285193726798e+01,'good','');
INSERT INTO "samples" VALUES(1,2,1641079860.0,'x4_c',4.64931651947289950035e+01,'good','');
INSERT INTO "samples" VALUES(1,2,1641079860.0,'x5_c',3.02033166887960184969e+01,'good','');
INSERT INTO "samples" VALUES(1,3,1641079920.0,'ghi_wm2',1.14322030944035446964e+02,'good','');
INSERT INTO "samples" VALUES(1,3,1641079920.0,'t_out_c',-3.7188803048487051317e-01,'good','');
INSERT INTO "samples" VALUES(1,3,1641079920.0,'t_room_c',2.19512785040895259665e+01,'good','');
INSERT INTO "samples" VALUES(1,3,1641079920.0,'v_cav_ms',1.67858397930467195813e-01,'good','');
INSERT INTO "samples" VALUES(1,3,1641079920.0,'wind_dir_deg',2.57902619616795220742e+02,'good','');
INSERT INTO "samples" VALUES(1,3,1641079920.0,'wind_speed_ms',4.44268704298599903523e+00,'good','');
INSERT INTO "samples" VALUES(1,3,1641079920.0,'x1_c',8.87887905513191277862e+00,'good','');
INSERT INTO "samples" VALUES(1,3,1641079920.0,'x2_c',46.0937901202721,'good','');
INSERT INTO "samples" VALUES(1,3,1641079920.0,'x3_c',2.84175751877143731869e+01,'good','');
INSERT INTO "samples" VALUES(1,3,1641079920.0,'x4_c',4.42657989952863175622e+01,'good','');
INSERT INTO "samples" VALUES(1,3,1641079920.0,'x5_c',2.98646458416680324896e+01,'good','');
INSERT INTO "samples" VALUES(1,4,1641079980.0,'ghi_wm2',1.17795822793605282181e+02,'good','');
INSERT INTO "samples" VALUES(1,4,1641079980.0,'t_out_c',-0.46958097859434,'good','');
INSERT INTO "samples" VALUES(1,4,1641079980.0,'t_room_c',2.186633515857746346e+01,'good','');
INSERT INTO "samples" VALUES(1,4,1641079980.0,'v_cav_ms',8.22821035137367706724e-02,'good','');
INSERT INTO "samples" VALUES(1,4,1641079980.0,'wind_dir_deg',2.53041435536474921272e+02,'good','');
INSERT INTO "samples" VALUES(1,4,1641079980.0,'wind_speed_ms',3.90536034736226822516e+00,'good','');
INSERT INTO "samples" VALUES(1,4,1641079980.0,'x1_c',8.51666301602746,'good','');
INSERT INTO "samples" VALUES(1,4,1641079980.0,'x2_c',4.55962702296070432339e+01,'good','');
INSERT INTO "samples" VALUES(1,4,1641079980.0,'x3_c',2.89178258384808763983e+01,'good','');
INSERT INTO "samples" VALUES(1,4,1641079980.0,'x4_c',4.14435043944740542096e+01,'good','');
INSERT INTO "samples" VALUES(1,4,1641079980.0,'x5_c',2.46150656551712181401e+01,'good','');
INSERT INTO "samples" VALUES(1,5,1641080040.0,'ghi_wm2',1.19897618145499805562e+02,'good','');
INSERT INTO "samples" VALUES(1,5,1641080040.0,'t_out_c',-3.31356226898953221127e-01,'good','');
INSERT INTO "samples" VALUES(1,5,1641080040.0,'t_room_c',2.18677749517868633697e+01,'good','');
INSERT INTO "samples" VALUES(1,5,1641080040.0,'v_cav_ms',7.19202674442158407241e-03,'good','');
INSERT INTO "samples" VALUES(1,5,1641080040.0,'wind_dir_deg',2.46844069194779450518e+02,'good','');
INSERT INTO "samples" VALUES(1,5,1641080040.0,'wind_speed_ms',3.21347648321846790508e+00,'good','');
INSERT INTO "samples" VALUES(1,5,1641080040.0,'x1_c',8.41987720805807171586e+00,'good','');
INSERT INTO "samples" VALUES(1,5,1641080040.0,'x2_c',4.53342825879997732849e+01,'good','');
INSERT INTO "samples" VALUES(1,5,1641080040.0,'x3_c',2.86627247914656067004e+01,'good','');
INSERT INTO "samples" VALUES(1,5,1641080040.0,'x4_c',3.9351873301482036993e+01,'good','');
INSERT INTO "samples" VALUES(1,5,1641080040.0,'x5_c',2.37226119867764886342e+01,'good','');
INSERT INTO "samples" VALUES(1,6,1641080100.0,'ghi_wm2',1.24541705647872390726e+02,'good','');
INSERT INTO "samples" VALUES(1,6,1641080100.0,'t_out_c',2.238133777480492137e-01,'good','');
INSERT INTO "samples" VALUES(1,6,1641080100.0,'t_room_c',2.21493658033175115922e+01,'good','');
INSERT INTO "samples" VALUES(1,6,1641080100.0,'v_cav_ms',4.06622941980655100424e-02,'good','');
INSERT INTO "samples" VALUES(1,6,1641080100.0,'wind_dir_deg',2.44597409802343094035e+02,'good','');
INSERT INTO "samples" VALUES(1,6,1641080100.0,'wind_speed_ms',3.38205703526221768129e+00,'good','');
INSERT INTO "samples" VALUES(1,6,1641080100.0,'x1_c',8.40013334146460088902e+00,'good','');
INSERT INTO "samples" VALUES(1,6,1641080100.0,'x2_c',4.47092910477550731229e+01,'good','');
INSERT INTO "samples" VALUES(1,6,1641080100.0,'x3_c',2.88601467293430289382e+01,'good','');
INSERT INTO "samples" VALUES(1,6,1641080100.0,'x4_c',3.81704582182264857692e+01,'good','');
INSERT INTO "samples" VALUES(1,6,1641080100.0,'x5_c',2.53164688629305096863e+01,'good','');
INSERT INTO "samples" VALUES(1,7,1641080160.0,'ghi_wm2',1.2811502442336401941e+02,'good','');
INSERT INTO "samples" VALUES(1,7,1641080160.0,'t_out_c',-1.57015289854003925462e-01,'good','');
INSERT INTO "samples" VALUES(1,7,1641080160.0,'t_room_c',2.17528729004163565727e+01,'good','');
INSERT INTO "samples" VALUES(1,7,1641080160.0,'v_cav_ms',4.51210269957730489287e-02,'good','');
INSERT INTO "samples" VALUES(1,7,1641080160.0,'wind_dir_deg',2.57650268482487888378e+02,'good','');
INSERT INTO "samples" VALUES(1,7,1641080160.0,'wind_speed_ms',3.58930200879398109137e+00,'good','');
INSERT INTO "samples" VALUES(1,7,1641080160.0,'x1_c',8.33916219777414369218e+00,'good','');
INSERT INTO "samples" VALUES(1,7,1641080160.0,'x2_c',4.41911730829021465183e+01,'good','');
INSERT INTO "samples" VALUES(1,7,1641080160.0,'x3_c',2.87895110654419710272e+01,'good','');
INSERT INTO "samples" VALUES(1,7,1641080160.0,'x4_c',3.72575506124443904813e+01,'good','');
INSERT INTO "samples" VALUES(1,7,1641080160.0,'x5_c',2.59250156053948792593e+01,'good','');
INSERT INTO "samples" VALUES(1,8,1641080220.0,'ghi_wm2',1.3185539003344027265e+02,'good','');
INSERT INTO "samples" VALUES(1,8,1641080220.0,'t_out_c',8.98818773216631394795e-02,'good','');
INSERT INTO "samples" VALUES(1,8,1641080220.0,'t_room_c',2.19662747207093502757e+01,'good','');
INSERT INTO "samples" VALUES(1,8,1641080220.0,'v_cav_ms',2.27166814187956568604e-02,'good','');
INSERT INTO "samples" VALUES(1,8,1641080220.0,'wind_dir_deg',2.55828552821446152175e+02,'good','');
INSERT INTO "samples" VALUES(1,8,1641080220.0,'wind_speed_ms',3.84696516100646412894e+00,'good','');
INSERT INTO "samples" VALUES(1,8,1641080220.0,'x1_c',8.1492458226900978957e+00,'good','');
INSERT INTO "samples" VALUES(1,8,1641080220.0,'x2_c',4.40671246176029853805e+01,'good','');
INSERT INTO "samples" VALUES(1,8,1641080220.0,'x3_c',2.86574036075403419943e+01,'good','');
INSERT INTO "samples" VALUES(1,8,1641080220.0,'x4_c',3.70000043615564280221e+01,'good','');
INSERT INTO "samples" VALUES(1,8,1641080220.0,'x5_c',2.63382228157914504156e+01,'good','');
INSERT INTO "samples" VALUES(1,9,1641080280.0,'ghi_wm2',1.34592235111754945366e+02,'good','');
INSERT INTO "samples" VALUES(1,9,1641080280.0,'t_out_c',-2.2649470159029172489e-01,'good','');
INSERT INTO "samples" VALUES(1,9,1641080280.0,'t_room_c',2.17060305134477111717e+01,'good','');
INSERT INTO "samples" VALUES(1,9,1641080280.0,'v_cav_ms',2.91364659984339260945e-02,'good','');
INSERT INTO "samples" VALUES(1,9,1641080280.0,'wind_dir_deg',2.60191099050110608448e+02,'good','');
INSERT INTO "samples" VALUES(1,9,1641080280.0,'wind_speed_ms',4.11864077339902490138e+00,'good','');
INSERT INTO "samples" VALUES(1,9,1641080280.0,'x1_c',8.10215258795337689434e+00,'good','');
INSERT INTO "samples" VALUES(1,9,1641080280.0,'x2_c',4.36755381625681238233e+01,'good','');
INSERT INTO "samples" VALUES(1,9,1641080280.0,'x3_c',2.88202642404931062012e+01,'good','');
INSERT INTO "samples" VALUES(1,9,1641080280.0,'x4_c',3.67550383866800700616e+01,'good','');
INSERT INTO "samples" VALUES(1,9,1641080280.0,'x5_c',2.71622895153396797245e+01,'good','');
INSERT INTO "samples" VALUES(1,10,1641080340.0,'ghi_wm2',1.37752932763647692124e+02,'good','');
INSERT INTO "samples" VALUES(1,10,1641080340.0,'t_out_c',1.07607231994262669827e-02,'good','');
INSERT INTO "samples" VALUES(1,10,1641080340.0,'t_room_c',2.16756800294230522752e+01,'good','');
INSERT INTO "samples" VALUES(1,10,1641080340.0,'v_cav_ms',2.13100358011021451254e-01,'good','');
INSERT INTO "samples" VALUES(1,10,1641080340.0,'wind_dir_deg',2.61122755061694874719e+02,'good','');
INSERT INTO "samples" VALUES(1,10,1641080340.0,'wind_speed_ms',4.63411112994083573823e+00,'good','');
INSERT INTO "samples" VALUES(1,10,1641080340.0,'x1_c',8.17754698488813,'good','');
INSERT INTO "samples" VALUES(1,10,1641080340.0,'x2_c',4.34064909739576236785e+01,'good','');
INSERT INTO "samples" VALUES(1,10,1641080340.0,'x3_c',2.86603152354782544355e+01,'good','');
INSERT INTO "samples" VALUES(1,10,1641080340.0,'x4_c',3.62630436859489648773e+01,'good','');
INSERT INTO "samples" VALUES(1,10,1641080340.0,'x5_c',1.17455262825284467709e+01,'good','');
INSERT INTO "samples" VALUES(1,11,1641080400.0,'ghi_wm2',1.41054668476726789098e+02,'good','');
INSERT INTO "samples" VALUES(1,11,1641080400.0,'t_out_c',-1.45356375708448837258e-01,'good','');
INSERT INTO "samples" VALUES(1,11,1641080400.0,'t_room_c',2.17588280204719914929e+01,'good','');
INSERT INTO "samples" VALUES(1,11,1641080400.0,'v_cav_ms',1.35693653380264428465e-01,'good','');
INSERT INTO "samples" VALUES(1,11,1641080400.0,'wind_dir_deg',2.5970279589874854765e+02,'good','');
INSERT INTO "samples" VALUES(1,11,1641080400.0,'wind_speed_ms',4.50684221129212,'good','');
INSERT INTO "samples" VALUES(1,11,1641080400.0,'x1_c',8.28035954667437579246e+00,'good','');
INSERT INTO "samples" VALUES(1,11,1641080400.0,'x2_c',4.29573913329281182899e+01,'good','');
INSERT INTO "samples" VALUES(1,11,1641080400.0,'x3_c',2.88441221514480972132e+01,'good','');
INSERT INTO "samples" VALUES(1,11,1641080400.0,'x4_c',3.57943305154088093895e+01,'good','');
INSERT INTO "samples" VALUES(1,11,1641080400.0,'x5_c',2.74685277839140873368e+01,'good','');
INSERT INTO "samples" VALUES(1,12,1641080460.0,'ghi_wm2',1.43489745095814782874e+02,'good','');
INSERT INTO "samples" VALUES(1,12,1641080460.0,'t_out_c',-2.34464062732845424097e-01,'good','');
INSERT INTO "samples" VALUES(1,12,1641080460.0,'t_room_c',2.19821604022612611113e+01,'good','');
INSERT INTO "samples" VALUES(1,12,1641080460.0,'v_cav_ms',1.71479652617755357058e-01,'good','');
INSERT INTO "samples" VALUES(1,12,1641080460.0,'wind_dir_deg',2.63452778078213668768e+02,'good','');
INSERT INTO "samples" VALUES(1,12,1641080460.0,'wind_speed_ms',4.30885691838643758444e+00,'good','');
INSERT INTO "samples" VALUES(1,12,1641080460.0,'x1_c',8.22404028112225,'good','');
INSERT INTO "samples" VALUES(1,12,1641080460.0,'x2_c',4.27139614867344903376e+01,'good','');
INSERT INTO "samples" VALUES(1,12,1641080460.0,'x3_c',2.8624768194494546237e+01,'good','');
INSERT INTO "samples" VALUES(1,12,1641080460.0,'x4_c',3.60669149661922929786e+01,'good','');
INSERT INTO "samples" VALUES(1,12,1641080460.0,'x5_c',2.74919134283597195174e+01,'good','');
INSERT INTO "samples" VALUES(1,13,1641080520.0,'ghi_wm2',1.46605973709512682036e+02,'good','');
INSERT INTO "samples" VALUES(1,13,1641080520.0,'t_out_c',-1.99022401720608504982e-01,'good','');
INSERT INTO "samples" VALUES(1,13,1641080520.0,'t_room_c',2.21817707168961462125e+01,'good','');
INSERT INTO "samples" VALUES(1,13,1641080520.0,'v_cav_ms',1.27838786814680804848e-01,'good','');
INSERT INTO "samples" VALUES(1,13,1641080520.0,'wind_dir_deg',267.542618093487,'good','');
INSERT INTO "samples" VALUES(1,13,1641080520.0,'wind_speed_ms',4.23182592522004075163e+00,'good','');
INSERT INTO "samples" VALUES(1,13,1641080520.0,'x1_c',8.40585628504952175887e+00,'good','');
INSERT INTO "samples" VALUES(1,13,1641080520.0,'x2_c',4.22832383042977681935e+01,'good','');
INSERT INTO "samples" VALUES(1,13,1641080520.0,'x3_c',2.83997564466701852836e+01,'good','');
INSERT INTO "samples" VALUES(1,13,1641080520.0,'x4_c',3.60877524011683377121e+01,'good','');
INSERT INTO "samples" VALUES(1,13,1641080520.0,'x5_c',2.75642342110266120864e+01,'good','');
INSERT INTO "samples" VALUES(1,14,1641080580.0,'ghi_wm2',1.48728317143225638114e+02,'good','');
INSERT INTO "samples" VALUES(1,14,1641080580.0,'t_out_c',5.78305399744097614611e-02,'good','');
INSERT INTO "samples" VALUES(1,14,1641080580.0,'t_room_c',2.17241978263861312825e+01,'good','');
INSERT INTO "samples" VALUES(1,14,1641080580.0,'v_cav_ms',1.3702081061417550889e-01,'good','');
INSERT INTO "samples" VALUES(1,14,1641080580.0,'wind_dir_deg',2.74186223719105839793e+02,'good','');
INSERT INTO "samples" VALUES(1,14,1641080580.0,'wind_speed_ms',4.13948477565739469952e+00,'good','');
INSERT INTO "samples" VALUES(1,14,1641080580.0,'x1_c',8.27978517020256710168e+00,'good','');
INSERT INTO "samples" VALUES(1,14,1641080580.0,'x2_c',4.21011441205944194612e+01,'good','');
INSERT INTO "samples" VALUES(1,14,1641080580.0,'x3_c',2.89054924791270870807e+01,'good','');
INSERT INTO "samples" VALUES(1,14,1641080580.0,'x4_c',3.62242474970808103762e+01,'good','');
INSERT INTO "samples" VALUES(1,14,1641080580.0,'x5_c',2.73315412543001379219e+01,'good','');
INSERT INTO "samples" VALUES(1,15,1641080640.0,'ghi_wm2',1.5119371785477881076e+02,'good','');
INSERT INTO "samples" VALUES(1,15,1641080640.0,'t_out_c',1.76668040930436809343e-01,'good','');
INSERT INTO "samples" VALUES(1,15,1641080640.0,'t_room_c',2.19043232865908770183e+01,'good','');
INSERT INTO "samples" VALUES(1,15,1641080640.0,'v_cav_ms',1.80673661191056239561e-01,'good','');
INSERT INTO "samples" VALUES(1,15,1641080640.0,'wind_dir_deg',2.76550357811529920579e+02,'good','');
INSERT INTO "samples" VALUES(1,15,1641080640.0,'wind_speed_ms',3.88499306854709836045e+00,'good','');
INSERT INTO "samples" VALUES(1,15,1641080640.0,'x1_c',8.39600811720626,'good','');
INSERT INTO "samples" VALUES(1,15,1641080640.0,'x2_c',4.18042334633354855082e+01,'good','');
INSERT INTO "samples" VALUES(1,15,1641080640.0,'x3_c',2.85541522967914147557e+01,'good','');
INSERT INTO "samples" VALUES(1,15,1641080640.0,'x4_c',3.67040699329695314641e+01,'good','');
INSERT INTO "samples" VALUES(1,15,1641080640.0,'x5_c',2.77545180850725259347e+01,'good','');
INSERT INTO "samples" VALUES(1,16,1641080700.0,'ghi_wm2',1.53278999982810631768e+02,'good','');
INSERT INTO "samples" VALUES(1,16,1641080700.0,'t_out_c',4.84477318670540751943e-02,'good','');
INSERT INTO "samples" VALUES(1,16,1641080700.0,'t_room_c',2.19107967141309494256e+01,'good','');
INSERT INTO "samples" VALUES(1,16,1641080700.0,'v_cav_ms',1.4294449659685690146e-01,'good','');
INSERT INTO "samples" VALUES(1,16,1641080700.0,'wind_dir_deg',2.73791579622484391618e+02,'good','');
INSERT INTO "samples" VALUES(1,16,1641080700.0,'wind_speed_ms',3.61548279026700170035e+00,'good','');
INSERT INTO "samples" VALUES(1,16,1641080700.0,'x1_c',8.15652570340623306321e+00,'good','');
INSERT INTO "samples" VALUES(1,16,1641080700.0,'x2_c',4.15986370541476730994e+01,'good','');
INSERT INTO "samples" VALUES(1,16,1641080700.0,'x3_c',2.88148973155383067998e+01,'good','');
INSERT INTO "samples" VALUES(1,16,1641080700.0,'x4_c',3.65960996002253580172e+01,'good','');
INSERT INTO "samples" VALUES(1,16,1641080700.0,'x5_c',2.79327714418180192987e+01,'good','');
INSERT INTO "samples" VALUES(1,17,1641080760.0,'ghi_wm2',1.58696029969370329122e+02,'good','');
INSERT INTO "samples" VALUES(1,17,1641080760.0,'t_out_c',-1.93511250583127347724e-01,'good','');
INSERT INTO "samples" VALUES(1,17,1641080760.0,'t_room_c',2.15061416168861327955e+01,'good','');
INSERT INTO "samples" VALUES(1,17,1641080760.0,'v_cav_ms',1.32859732572702227137e-01,'good','');
INSERT INTO "samples" VALUES(1,17,1641080760.0,'wind_dir_deg',2.81458870775819946178e+02,'good','');
INSERT INTO "samples" VALUES(1,17,1641080760.0,'wind_speed_ms',3.55706248366075605815e+00,'good','');
INSERT INTO "samples" VALUES(1,17,1641080760.0,'x1_c',8.39075974778774380524e+00,'good','');
INSERT INTO "samples" VALUES(1,17,1641080760.0,'x2_c',4.11636830472526469302e+01,'good','');
INSERT INTO "samples" VALUES(1,17,1641080760.0,'x3_c',2.90299199802275929025e+01,'good','');
INSERT INTO "samples" VALUES(1,17,1641080760.0,'x4_c',3.62356381310023394353e+01,'good','');
INSERT INTO "samples" VALUES(1,17,1641080760.0,'x5_c',2.78571693380236879984e+01,'good','');
INSERT INTO "samples" VALUES(1,18,1641080820.0,'ghi_wm2',1.59280878872387091863e+02,'good','');
INSERT INTO "samples" VALUES(1,18,1641080820.0,'t_out_c',5.12855512688340647864e-02,'good','');
INSERT INTO "samples" VALUES(1,18,1641080820.0,'t_room_c',2.16584182688512605352e+01,'good','');
INSERT INTO "samples" VALUES(1,18,1641080820.0,'v_cav_ms',1.7082845044515976296e-01,'good','');
INSERT INTO "samples" VALUES(1,18,1641080820.0,'wind_dir_deg',2.71302490897067798418e+02,'good','');
INSERT INTO "samples" VALUES(1,18,1641080820.0,'wind_speed_ms',2.86462234124166581494e+00,'good','');
INSERT INTO "samples" VALUES(1,18,1641080820.0,'x1_c',8.12222394279133652617e+00,'good','');
INSERT INTO "samples" VALUES(1,18,1641080820.0,'x2_c',4.10410643493877813625e+01,'good','');
INSERT INTO "samples" VALUES(1,18,1641080820.0,'x3_c',2.85643096133446796605e+01,'good','');
INSERT INTO "samples" VALUES(1,18,1641080820.0,'x4_c',3.62413124990845076918e+01,'good','');
INSERT INTO "samples" VALUES(1,18,1641080820.0,'x5_c',2.71759145151667240729e+01,'good','');
INSERT INTO "samples" VALUES(1,19,1641080880.0,'ghi_wm2',1.6266410556174480461e+02,'good','');
INSERT INTO "samples" VALUES(1,19,1641080880.0,'t_out_c',1.04138353601204033949e-01,'good','');
INSERT INTO "samples" VALUES(1,19,1641080880.0,'t_room_c',2.18352284710036919084e+01,'good','');
INSERT INTO "samples" VALUES(1,19,1641080880.0,'v_cav_ms',1.81511466292175099868e-01,'good','');
INSERT INTO "samples" VALUES(1,19,1641080880.0,'wind_dir_deg',2.71560855321644623928e+02,'good','');
INSERT INTO "samples" VALUES(1,19,1641080880.0,'wind_speed_ms',2.82814452277760164378e+00,'good','');
INSERT INTO "samples" VALUES(1,19,1641080880.0,'x1_c',8.21853627431879,'good','');
INSERT INTO "samples" VALUES(1,19,1641080880.0,'x2_c',4.13475949963999269689e+01,'good','');
INSERT INTO "samples" VALUES(1,19,1641080880.0,'x3_c',2.86515516400935439378e+01,'good','');
INSERT INTO "samples" VALUES(1,19,1641080880.0,'x4_c',3.68209370966121625197e+01,'good','');
INSERT INTO "samples" VALUES(1,19,1641080880.0,'x5_c',2.77737420007973412339e+01,'good','');
INSERT INTO "samples" VALUES(1,20,1641080940.0,'ghi_wm2',1.6622492595601065091e+02,'good','');
INSERT INTO "samples" VALUES(1,20,1641080940.0,'t_out_c',4.49369394173337488584e-01,'good','');
INSERT INTO "samples" VALUES(1,20,1641080940.0,'t_room_c',2.18304750861808898325e+01,'good','');
INSERT INTO "samples" VALUES(1,20,1641080940.0,'v_cav_ms',1.90743687686264540293e-01,'good','');
INSERT INTO "samples" VALUES(1,20,1641080940.0,'wind_dir_deg',2.6974163984116859183e+02,'good','');
INSERT INTO "samples" VALUES(1,20,1641080940.0,'wind_speed_ms',2.50130293436231943005e+00,'good','');
INSERT INTO "samples" VALUES(1,20,1641080940.0,'x1_c',8.32780395260625283526e+00,'good','');
INSERT INTO "samples" VALUES(1,20,1641080940.0,'x2_c',4.12353718241958802073e+01,'good','');
INSERT INTO "samples" VALUES(1,20,1641080940.0,'x3_c',2.8931828710988380493e+01,'good','');
INSERT INTO "samples" VALUES(1,20,1641080940.0,'x4_c',3.65003264553717770017e+01,'good','');
INSERT INTO "samples" VALUES(1,20,1641080940.0,'x5_c',2.75509212409416797133e+01,'good','');
CREATE INDEX samples_by_time ON samples (time_s, signal);
CREATE INDEX decisions_by_time ON decisions (time_s);
CREATE INDEX comfort_by_time ON comfort (time_s);
CREATE INDEX commands_pending ON commands (status, command_id);
CREATE INDEX findings_by_state ON findings (state, kind);
DELETE FROM "sqlite_sequence";
INSERT INTO "sqlite_sequence" VALUES('runs',1);
COMMIT;
