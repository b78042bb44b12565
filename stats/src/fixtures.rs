//! Stored results for tests (this crate's, and with the `test-support` feature other crates'):
//! rows made as the store reads them.

use crate::StoredResult;

/// A stored run of `label` on `building` with seed `seed` that explored in `time_s`.
pub fn stored(building: &str, label: &str, seed: u64, time_s: f64) -> StoredResult {
    // A real summary (small.toml, layout, seed 1) with the time replaced.
    let template: &str = concat!(
        r#"{"format":"floorcast-run-summary","version":1,"floorcast_version":"0.1.0","build"#,
        r#"ing":"small","building_hash":"bd6183b04c0805da57279aa53b7844c1","strategy":"layo"#,
        r#"ut","seed":1,"settings":{"robot_radius_m":0.2,"max_speed_mps":0.5,"max_turn_rate"#,
        r#"_radps":1.0,"laser_fov_deg":180.0,"laser_range_m":6.0,"laser_beams":181,"laser_r"#,
        r#"ate_hz":10.0,"laser_noise_sd_m":0.01,"odometry_translation_error":0.01,"odometry"#,
        r#"_rotation_error_deg_per_rad":2.0,"localization":"slam","map_resolution_m":0.05,""#,
        r#"alpha":0.5,"min_frontier_m":0.5,"redecide_period_s":10.0,"blacklist_radius_m":0."#,
        r#"5,"progress_timeout_s":20.0,"time_limit_s":14400.0,"return_home":false,"es_thres"#,
        r#"hold_m2":1.0,"aes_min_gain_m2":2.0,"layout_update_m2":20.0},"start":[1.199999999"#,
        r#"9999993,9.81368055441612,0.0],"start_source":"building file","exploration_time_s"#,
        r#"":606.2000000000693,"total_time_s":606.2000000000693,"explored_area_m2":407.9825"#,
        r#"000000001,"free_area_m2":408.2100000000001,"explored_fraction":0.999442688812131"#,
        r#","path_length_m":265.2573756983305,"decisions":166,"stopped_early":false,"unexpl"#,
        r#"ored_free_m2":0.22750000000002046,"rooms_never_entered":0,"layouts_computed":17,"#,
        r#""end_reason":"no frontiers","blacklisted_goals":0,"scans":3341,"scan_matches_acc"#,
        r#"epted":3220,"map_free_precision":0.9946381028273507,"map_occupied_precision":0.8"#,
        r#"890061565523307,"wall_time_s":11.839814543,"speedup":51.200126302524744}"#,
    );
    let mut summary: serde_json::Value = serde_json::from_str(template).unwrap();
    summary["exploration_time_s"] = serde_json::json!(time_s);
    summary["total_time_s"] = serde_json::json!(time_s);
    StoredResult {
        job_id: format!("{building}-{label}-{seed}"),
        grid: "g".into(),
        building: building.into(),
        building_hash: "h".into(),
        strategy: label.into(),
        label: label.into(),
        seed,
        settings: floorcast_worker::Settings::default(),
        status: floorcast_worker::wire::JobStatus::Ok,
        error: None,
        summary: Some(floorcast_worker::RunSummary::from_json(&summary.to_string()).unwrap()),
        progress: None,
        worker: "w".into(),
        wall_time_s: 1.0,
        floorcast_version: "0".into(),
        stderr_tail: None,
    }
}

/// A stored row's summary as its JSON, to edit it as a record's text.
pub fn summary_value(r: &StoredResult) -> serde_json::Value {
    serde_json::to_value(r.summary.as_ref().unwrap()).unwrap()
}

/// Sets a row's summary from its JSON, read as the store reads it.
pub fn set_summary(r: &mut StoredResult, v: &serde_json::Value) {
    r.summary = Some(floorcast_worker::RunSummary::from_json(&v.to_string()).unwrap());
}

/// A progress curve from its stored text.
pub fn progress(text: &str) -> Vec<crate::progress::Sample> {
    crate::progress::decode(text).unwrap()
}
