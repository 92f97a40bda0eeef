-- A real schema-1 database: 'dsfd run --dry-run --plant sim --plant-fidelity lumped --cycles 3'
-- of dsfd at commit 7954a8e (before schema 2), dumped with sqlite3 .dump; tests/storage rebuild it.
PRAGMA foreign_keys=OFF;
BEGIN TRANSACTION;
CREATE TABLE meta (
    key TEXT PRIMARY KEY,
    value TEXT NOT NULL
);
INSERT INTO meta VALUES('schema_version','1');
INSERT INTO meta VALUES('created_utc','2026-11-25T07:45:46Z');
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
    cycles INTEGER
);
INSERT INTO runs VALUES(1,'suwon-south','dry run, simulated plant, lumped','2026-11-25T07:45:46Z',30365,'0.1.0','config/panels/suwon-south.yaml','2026-11-25T07:45:46Z','cycles done',3);
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
INSERT INTO samples VALUES(1,1,1641079800.0,'ghi_wm2',108.50844716809473311,'good','');
INSERT INTO samples VALUES(1,1,1641079800.0,'t_out_c',-0.3964275370270441412,'good','');
INSERT INTO samples VALUES(1,1,1641079800.0,'t_room_c',21.608748634490947183,'good','');
INSERT INTO samples VALUES(1,1,1641079800.0,'v_cav_ms',0.018565924258910834754,'good','');
INSERT INTO samples VALUES(1,1,1641079800.0,'wind_dir_deg',258.51922339176570632,'good','');
INSERT INTO samples VALUES(1,1,1641079800.0,'wind_speed_ms',5.6620992883441125798,'good','');
INSERT INTO samples VALUES(1,1,1641079800.0,'x1_c',9.0929502206002261743,'good','');
INSERT INTO samples VALUES(1,1,1641079800.0,'x2_c',46.51848485529288979,'good','');
INSERT INTO samples VALUES(1,1,1641079800.0,'x3_c',28.763333802422799578,'good','');
INSERT INTO samples VALUES(1,1,1641079800.0,'x4_c',49.715543746810880064,'good','');
INSERT INTO samples VALUES(1,1,1641079800.0,'x5_c',43.520418952247950984,'good','');
INSERT INTO samples VALUES(1,2,1641079860.0,'ghi_wm2',109.69467571710646325,'good','');
INSERT INTO samples VALUES(1,2,1641079860.0,'t_out_c',-0.27907555758489954733,'good','');
INSERT INTO samples VALUES(1,2,1641079860.0,'t_room_c',21.689983244239694926,'good','');
INSERT INTO samples VALUES(1,2,1641079860.0,'v_cav_ms',0.20580465698188327161,'good','');
INSERT INTO samples VALUES(1,2,1641079860.0,'wind_dir_deg',256.13444885253471739,'good','');
INSERT INTO samples VALUES(1,2,1641079860.0,'wind_speed_ms',5.1446597387584276361,'good','');
INSERT INTO samples VALUES(1,2,1641079860.0,'x1_c',8.8421696859330563,'good','');
INSERT INTO samples VALUES(1,2,1641079860.0,'x2_c',46.046591602562259026,'good','');
INSERT INTO samples VALUES(1,2,1641079860.0,'x3_c',28.390820685518217913,'good','');
INSERT INTO samples VALUES(1,2,1641079860.0,'x4_c',46.848982897424271245,'good','');
INSERT INTO samples VALUES(1,2,1641079860.0,'x5_c',31.129536421237286702,'good','');
INSERT INTO samples VALUES(1,3,1641079920.0,'ghi_wm2',114.32203094403544696,'good','');
INSERT INTO samples VALUES(1,3,1641079920.0,'t_out_c',-0.37188803048487051317,'good','');
INSERT INTO samples VALUES(1,3,1641079920.0,'t_room_c',21.951278504089525966,'good','');
INSERT INTO samples VALUES(1,3,1641079920.0,'v_cav_ms',0.17777847475699276591,'good','');
INSERT INTO samples VALUES(1,3,1641079920.0,'wind_dir_deg',257.90261961679522074,'good','');
INSERT INTO samples VALUES(1,3,1641079920.0,'wind_speed_ms',4.4426870429859990352,'good','');
INSERT INTO samples VALUES(1,3,1641079920.0,'x1_c',8.8973739854018933925,'good','');
INSERT INTO samples VALUES(1,3,1641079920.0,'x2_c',46.117579918544826965,'good','');
INSERT INTO samples VALUES(1,3,1641079920.0,'x3_c',28.405849122350286251,'good','');
INSERT INTO samples VALUES(1,3,1641079920.0,'x4_c',44.854302277026690147,'good','');
INSERT INTO samples VALUES(1,3,1641079920.0,'x5_c',30.782457904040239071,'good','');
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
    PRIMARY KEY (run_id, cycle)
);
INSERT INTO decisions VALUES(1,1,0,1641079800.0,'2022-01-01T23:30:00Z','mpc','',1,-1331708.4609702797606,18.0,1,100.0,18.0,1,100.0,'verified','[]','[{"stage":"decide:mpc","set":{"phi_deg":18.0,"afr":1,"or_pct":100.0},"why":"candidates: 11 louver positions x 6 damper sets (regimes [1, 3, 5, 6, 9, 10]), OR grid [0.0, 100.0] % | stage 1: screened 121 candidates at 300 s steps | stage 2: 14 at full resolution (10 finalists, OR brackets of 2 pairs), best louver +18 deg, regime 1, OR 100.0 %, J -369.92 Wh | stage 3: not needed (the best''s louver neighbours were evaluated)"},{"stage":"faults","set":{},"why":"no fault"},{"stage":"wind","set":{},"why":"wind 5.7 m/s below 15 m/s"},{"stage":"limits","set":{},"why":"louver -90..90 deg, dampers 0..100 %"},{"stage":"quantisation","set":{},"why":"louver onto the 18 deg motor grid, dampers onto 1 % steps"},{"stage":"rate","set":{},"why":"within rate limits"},{"stage":"regimes","set":{},"why":"regime 1 available"}]','{"read":1.764,"quality":4.104,"estimate":0.969,"calibrate":0.017,"decide":42.592,"safety":0.104,"write":0.11}',49.659999999999996588,0);
INSERT INTO decisions VALUES(1,2,1,1641079860.0,'2022-01-01T23:31:00Z','mpc','',1,-1272127.3408331025857,18.0,1,100.0,18.0,1,100.0,'verified','[]','[{"stage":"decide:mpc","set":{"phi_deg":18.0,"afr":1,"or_pct":100.0},"why":"candidates: 11 louver positions x 6 damper sets (regimes [1, 3, 5, 6, 9, 10]), OR grid [0.0, 100.0] % | stage 1: screened 121 candidates at 300 s steps | stage 2: 15 at full resolution (10 finalists, OR brackets of 2 pairs), best louver +18 deg, regime 1, OR 100.0 %, J -353.37 Wh | stage 3: not needed (the best''s louver neighbours were evaluated)"},{"stage":"faults","set":{},"why":"no fault"},{"stage":"wind","set":{},"why":"wind 5.1 m/s below 15 m/s"},{"stage":"limits","set":{},"why":"louver -90..90 deg, dampers 0..100 %"},{"stage":"quantisation","set":{},"why":"louver onto the 18 deg motor grid, dampers onto 1 % steps"},{"stage":"rate","set":{},"why":"within rate limits"},{"stage":"regimes","set":{},"why":"regime 1 available"}]','{"read":26.944,"quality":0.042,"estimate":2.279,"calibrate":0.019,"decide":41.926,"safety":0.113,"write":0.12}',71.44300000000001205,0);
INSERT INTO decisions VALUES(1,3,2,1641079920.0,'2022-01-01T23:32:00Z','mpc','',1,-1270168.7473107010591,18.0,7,100.0,18.0,7,100.0,'verified','[]','[{"stage":"decide:mpc","set":{"phi_deg":18.0,"afr":7,"or_pct":100.0},"why":"candidates: 11 louver positions x 6 damper sets (regimes [1, 3, 5, 6, 9, 10]), OR grid [0.0, 100.0] % | stage 1: screened 121 candidates at 300 s steps | stage 2: 16 at full resolution (10 finalists, OR brackets of 2 pairs), best louver +18 deg, regime 7, OR 100.0 %, J -352.82 Wh | stage 3: not needed (the best''s louver neighbours were evaluated)"},{"stage":"faults","set":{},"why":"no fault"},{"stage":"wind","set":{},"why":"wind 4.4 m/s below 15 m/s"},{"stage":"limits","set":{},"why":"louver -90..90 deg, dampers 0..100 %"},{"stage":"quantisation","set":{},"why":"louver onto the 18 deg motor grid, dampers onto 1 % steps"},{"stage":"rate","set":{},"why":"within rate limits"},{"stage":"regimes","set":{},"why":"regime 7 available"}]','{"read":2.646,"quality":1.896,"estimate":1.527,"calibrate":0.015,"decide":39.118,"safety":0.095,"write":0.108}',45.404999999999994032,0);
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
INSERT INTO parameters VALUES(1,1,1641079800.0,'prior',12.0,3.5,4.0,3.5,4.4000000000000003552,2.5,100.0,0.050000000000000002775,0.59999999999999997779,'{"q_x1":0.0,"q_x2":0.0,"q_x3":0.0,"q_x4":0.0}',NULL,'no calibration state at /tmp/v1/calibration.json: starting from the panel priors');
CREATE TABLE events (
    event_id INTEGER PRIMARY KEY AUTOINCREMENT,
    run_id INTEGER NOT NULL REFERENCES runs(run_id),
    cycle INTEGER NOT NULL,
    time_s REAL NOT NULL,
    level TEXT NOT NULL,
    kind TEXT NOT NULL,
    message TEXT NOT NULL
);
DELETE FROM sqlite_sequence;
INSERT INTO sqlite_sequence VALUES('runs',1);
CREATE INDEX samples_by_time ON samples (time_s, signal);
CREATE INDEX decisions_by_time ON decisions (time_s);
COMMIT;
