//! A store's runs as a file small enough to commit: `report DIR --export-runs FILE` writes the
//! successful runs and the tours of a results store, `run GRID --import FILE` stores those of
//! them that are jobs of the grid before running the others. A leaderboard's runs travel with
//! the repository this way, so that a new strategy's author runs only their own jobs.
//!
//! The file is gzip-compressed JSON lines: a header (`format = "floorcast-runs"`, `version`,
//! floorcast's version, how many runs and tours follow), then one line per run (the store's
//! columns, the settings and summary as JSON) and one per tour ([`TourRecord`]). Each progress
//! curve is thinned ([`thin`]) to the first sample at each whole percent explored below 95 %
//! and at each tenth of a percent from there, and the last sample: a run's times to whole
//! percents (and to every tenth from 95 %) are those of the full curve, its exploration time,
//! end and summary too; the area above the curve (`unexplored_area_s`) and the progress charts
//! are approximations. Every line is checked on the way in as a store's row is (the row's
//! summary against its seed and building, the tour's record), and sizes are bounded before
//! anything is allocated.

use std::io::{BufRead, BufReader, Read, Write};
use std::path::Path;

use floorcast_worker::tour::TourRecord;
use floorcast_worker::FLOORCAST_VERSION;
use serde::{Deserialize, Serialize};

use crate::store::{decode_exported, JobStatus, StoredResult};
use floorcast_stats::progress::Sample;

pub const RUNS_FORMAT: &str = "floorcast-runs";
pub const RUNS_VERSION: u32 = 1;
/// Most bytes of one line once decompressed (a run's summary and its thinned curve take a few
/// kilobytes; a tour's path a few hundred).
pub const MAX_LINE_BYTES: u64 = 4 << 20;
/// Most bytes of the whole file once decompressed (the leaderboard's 1215 runs take 7 MB).
pub const MAX_TOTAL_BYTES: u64 = 256 << 20;

/// The first line of the file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Header {
    pub format: String,
    pub version: u32,
    /// The floorcast that wrote the file (the runs' own versions are in their lines).
    pub floorcast_version: String,
    pub runs: u64,
    pub tours: u64,
}

/// A run as the file holds it: a store's row, its JSON columns as JSON.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct RunLine {
    job_id: String,
    grid: String,
    building: String,
    building_hash: String,
    strategy: String,
    label: String,
    seed: u64,
    settings: serde_json::Value,
    summary: serde_json::Value,
    /// The thinned curve, as the store's CSV.
    progress: String,
    worker: String,
    wall_time_s: f64,
    floorcast_version: String,
}

/// One line after the header.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, rename_all = "snake_case")]
enum Line {
    Run(Box<RunLine>),
    Tour(Box<TourRecord>),
}

/// What a file holds, checked.
#[derive(Debug, Clone, PartialEq)]
pub struct Exported {
    pub header: Header,
    /// Successful runs, each with its thinned curve.
    pub runs: Vec<StoredResult>,
    /// The line of the file each of `runs` was read from (1 is the header).
    pub run_lines: Vec<usize>,
    pub tours: Vec<TourRecord>,
}

/// The samples of `curve` that the file keeps: the first, the first at or above each whole
/// percent explored below 95 % and each tenth of a percent from 95 %, and the last. Times to
/// those fractions ([`floorcast_stats::metric::time_to_fraction`]) are kept exactly.
pub fn thin(curve: &[Sample]) -> Vec<Sample> {
    // The level a fraction has reached: whole percents, then tenths of a percent from 95 %.
    let level = |f: f64| -> i64 {
        let per_mille = (f * 1000.0 + 1e-9).floor() as i64;
        if per_mille < 950 {
            per_mille / 10
        } else {
            95 + (per_mille - 950)
        }
    };
    let mut out: Vec<Sample> = Vec::new();
    let mut reached = i64::MIN;
    for (i, s) in curve.iter().enumerate() {
        let l = level(s.explored_fraction);
        if i == 0 || l > reached || i + 1 == curve.len() {
            out.push(*s);
        }
        reached = reached.max(l);
    }
    out
}

/// The successful runs among `rows` and the `tours` of the current method as the export file's
/// bytes (gzip JSON lines), with how many runs and tours it holds. The binary writes them the
/// way it writes every output (`src/output.rs`: through a link, directly to a device).
pub fn export(
    rows: &[StoredResult],
    tours: &[TourRecord],
) -> Result<(Vec<u8>, usize, usize), String> {
    let runs: Vec<&StoredResult> = rows.iter().filter(|r| r.status == JobStatus::Ok).collect();
    // A tour of an older method is never used again.
    let tours: Vec<&TourRecord> = tours
        .iter()
        .filter(|t| t.key.method == sim_core::tour::TOUR_METHOD)
        .collect();
    let header = Header {
        format: RUNS_FORMAT.into(),
        version: RUNS_VERSION,
        floorcast_version: FLOORCAST_VERSION.into(),
        runs: runs.len() as u64,
        tours: tours.len() as u64,
    };
    let mut lines = vec![serde_json::to_string(&header).map_err(|e| e.to_string())?];
    for r in &runs {
        let line = Line::Run(Box::new(RunLine {
            job_id: r.job_id.clone(),
            grid: r.grid.clone(),
            building: r.building.clone(),
            building_hash: r.building_hash.clone(),
            strategy: r.strategy.clone(),
            label: r.label.clone(),
            seed: r.seed,
            settings: serde_json::to_value(&r.settings).map_err(|e| e.to_string())?,
            summary: serde_json::to_value(&r.summary).map_err(|e| e.to_string())?,
            progress: floorcast_stats::progress::encode(&thin(
                r.progress.as_deref().unwrap_or(&[]),
            )),
            worker: r.worker.clone(),
            wall_time_s: r.wall_time_s,
            floorcast_version: r.floorcast_version.clone(),
        }));
        lines.push(serde_json::to_string(&line).map_err(|e| e.to_string())?);
    }
    for t in &tours {
        lines.push(
            serde_json::to_string(&Line::Tour(Box::new((*t).clone())))
                .map_err(|e| e.to_string())?,
        );
    }
    let encode = || -> std::io::Result<Vec<u8>> {
        let mut gz = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::best());
        for l in &lines {
            gz.write_all(l.as_bytes())?;
            gz.write_all(b"\n")?;
        }
        gz.finish()
    };
    let bytes = encode().map_err(|e| format!("cannot compress the export: {e}"))?;
    Ok((bytes, runs.len(), tours.len()))
}

/// Reads and checks a file [`export`] wrote. The error names the line and what was expected.
/// Only a regular file is read (a FIFO, which would block until written, or a device is
/// refused before it is opened), and only one gzip stream: bytes after it (another gzip member,
/// anything appended) are refused.
pub fn read(path: &Path) -> Result<Exported, String> {
    match std::fs::metadata(path) {
        Ok(m) if !m.is_file() => {
            return Err(
                "not a regular file (a directory, FIFO or device); expected a file that `floorcast report DIR --export-runs FILE` wrote"
                    .into(),
            )
        }
        _ => {}
    }
    let file = std::fs::File::open(path).map_err(|e| format!("cannot open it ({e})"))?;
    let gz = flate2::bufread::GzDecoder::new(BufReader::new(file));
    let mut input = BufReader::new(gz.take(MAX_TOTAL_BYTES + 1));
    let mut header: Option<Header> = None;
    let (mut runs, mut tours, mut run_lines) = (Vec::new(), Vec::new(), Vec::new());
    let mut buf = Vec::new();
    let mut total = 0u64;
    for n in 1.. {
        buf.clear();
        let got = (&mut input)
            .take(MAX_LINE_BYTES + 1)
            .read_until(b'\n', &mut buf)
            .map_err(|e| format!("line {n}: cannot read it ({e}); expected a gzip file of JSON lines that `floorcast report DIR --export-runs FILE` writes"))?;
        if got == 0 {
            break;
        }
        total += got as u64;
        if got as u64 > MAX_LINE_BYTES {
            return Err(format!("line {n}: longer than {MAX_LINE_BYTES} bytes"));
        }
        if total > MAX_TOTAL_BYTES {
            return Err(format!(
                "more than {MAX_TOTAL_BYTES} bytes once decompressed"
            ));
        }
        let text = std::str::from_utf8(&buf)
            .map_err(|_| format!("line {n}: not UTF-8"))?
            .trim_end();
        if n == 1 {
            let h: Header = serde_json::from_str(text).map_err(|e| {
                format!("line 1: expected the header {{\"format\": \"{RUNS_FORMAT}\", ...}} ({e})")
            })?;
            if h.format != RUNS_FORMAT {
                return Err(format!(
                    "line 1: format is \"{}\", expected \"{RUNS_FORMAT}\"",
                    floorcast_worker::text::excerpt(&h.format)
                ));
            }
            if h.version != RUNS_VERSION {
                return Err(format!(
                    "line 1: version is {}, expected {RUNS_VERSION}",
                    h.version
                ));
            }
            header = Some(h);
            continue;
        }
        let line: Line = serde_json::from_str(text)
            .map_err(|e| format!("line {n}: expected a run or a tour ({e})"))?;
        match line {
            Line::Run(r) => {
                runs.push(run_of(*r).map_err(|e| format!("line {n}: {e}"))?);
                run_lines.push(n);
            }
            Line::Tour(t) => {
                t.validate().map_err(|e| format!("line {n}: tour: {e}"))?;
                tours.push(*t);
            }
        }
    }
    // The gzip stream ended: nothing may follow it.
    let mut rest = input.into_inner().into_inner().into_inner();
    let after = rest
        .fill_buf()
        .map_err(|e| format!("cannot read it ({e})"))?
        .len();
    if after > 0 {
        return Err(
            "bytes follow the end of its gzip stream (another gzip member, or data appended); expected the one stream that `floorcast report DIR --export-runs FILE` writes"
                .into(),
        );
    }
    let header = header.ok_or("it is empty, expected the header line")?;
    if (header.runs, header.tours) != (runs.len() as u64, tours.len() as u64) {
        return Err(format!(
            "the header announces {} runs and {} tours, the file holds {} and {}: it was cut short or changed",
            header.runs,
            header.tours,
            runs.len(),
            tours.len()
        ));
    }
    Ok(Exported {
        header,
        runs,
        run_lines,
        tours,
    })
}

/// Checks an imported run against the grid's job it claims (its `job_id`): everything that
/// determines the run (building hash, strategy and program, seed, settings, start, floorcast
/// version) is the job's, its summary is whole and in range
/// ([`floorcast_worker::wire::check_report`], as for a remote worker's result), and its progress
/// curve agrees with its summary (times from 0 never going back, fractions in [0, 1], the last
/// sample the summary's explored fraction at its exploration time). The error names the field.
/// `starts` keeps the buildings' own starts found so far (by building and robot radius).
pub fn check_import(
    plan: &crate::grid::Plan,
    job: &crate::grid::PlannedJob,
    r: &StoredResult,
    starts: &mut Starts,
) -> Result<(), String> {
    let want = crate::execute::identity(plan, job);
    // Where the job starts: the grid's given start, else the building's own.
    let start = match &job.start {
        Some(g) => (
            [g.pose.x_m, g.pose.y_m, g.pose.theta_rad],
            g.source.as_str().to_string(),
        ),
        None => starts
            .entry((job.building, job.settings.robot_radius_m.to_bits()))
            .or_insert_with(|| {
                floorcast_worker::check_job(&crate::execute::spec(plan, job))
                    .map(|(_, p, source)| ([p.x_m, p.y_m, p.theta_rad], source))
                    .map_err(|e| e.to_string())
            })
            .clone()
            .map_err(|e| format!("the grid's job {} cannot run here ({e})", job.id))?,
    };
    let differs = |field: &str, got: &dyn std::fmt::Debug, want: &dyn std::fmt::Debug| {
        Err(format!(
            "field {field} is {got:?}, the grid's job {} has {want:?}",
            job.id
        ))
    };
    if r.building_hash != want.building_hash {
        return differs("building_hash", &r.building_hash, &want.building_hash);
    }
    if r.strategy != want.strategy {
        return differs("strategy", &r.strategy, &want.strategy);
    }
    if r.seed != want.seed {
        return differs("seed", &r.seed, &want.seed);
    }
    if r.settings != want.settings {
        return Err(format!(
            "field settings differs from the settings of the grid's job {}",
            job.id
        ));
    }
    // A run of an earlier floorcast is this one's while its strategy's runs have not changed
    // since (the version its job identity names, `floorcast_worker::runs_version`).
    if !floorcast_worker::runs_as_this_build(&r.strategy, &r.floorcast_version) {
        return differs(
            "floorcast_version",
            &r.floorcast_version,
            &format!(
                "{} to {FLOORCAST_VERSION}",
                floorcast_worker::runs_version(&r.strategy)
            ),
        );
    }
    let (Some(summary), Some(curve)) = (&r.summary, &r.progress) else {
        return Err("a successful run without its summary or progress curve".into());
    };
    let same_program = match (summary.strategy_program.as_ref(), job.program()) {
        (Some(a), Some(b)) => a.same_identity(b),
        (a, b) => a.is_none() && b.is_none(),
    };
    if !same_program {
        return Err(format!(
            "field summary.strategy_program differs from the grid's job {}'s program",
            job.id
        ));
    }
    let report = floorcast_worker::wire::JobReport {
        wall_time_s: r.wall_time_s,
        outcome: floorcast_worker::wire::JobOutcome::Ok {
            summary: Box::new(summary.clone()),
            progress: curve
                .iter()
                .map(|s| [s.time_s, s.explored_area_m2, s.explored_fraction])
                .collect(),
        },
        stderr_tail: None,
    };
    floorcast_worker::wire::check_report(&report, &want)
        .map_err(|e| format!("{e} (job {})", job.id))?;
    if summary.start.map(f64::to_bits) != start.0.map(f64::to_bits)
        || summary.start_source != start.1
    {
        return Err(format!(
            "field summary.start is {:?} ({}), the grid's job {} starts at {:?} ({})",
            summary.start, summary.start_source, job.id, start.0, start.1
        ));
    }
    check_curve(summary, curve)
}

/// A progress curve agrees with its run's summary (the curve as the store rounds it: time to
/// 0.1 s, fraction to five decimals).
fn check_curve(summary: &floorcast_worker::RunSummary, curve: &[Sample]) -> Result<(), String> {
    let Some(last) = curve.last() else {
        return Err("field progress is empty".into());
    };
    let mut before = 0.0;
    for (i, s) in curve.iter().enumerate() {
        if s.time_s.is_nan() || s.time_s < before {
            return Err(format!(
                "field progress: sample {} is at {} s, before the one before it ({before} s)",
                i + 1,
                s.time_s
            ));
        }
        before = s.time_s;
        if !(0.0..=1.0).contains(&s.explored_fraction)
            || s.explored_area_m2.is_nan()
            || s.explored_area_m2 < 0.0
        {
            return Err(format!(
                "field progress: sample {} has explored fraction {} and area {} m2, expected a fraction in [0, 1] and an area of 0 or more",
                i + 1,
                s.explored_fraction,
                s.explored_area_m2
            ));
        }
    }
    if (last.explored_fraction - summary.explored_fraction).abs() > CURVE_FRACTION_TOLERANCE {
        return Err(format!(
            "field summary.explored_fraction is {}, its progress curve ends at {}",
            summary.explored_fraction, last.explored_fraction
        ));
    }
    if (last.time_s - summary.exploration_time_s).abs() > CURVE_TIME_TOLERANCE_S {
        return Err(format!(
            "field summary.exploration_time_s is {} s, its progress curve ends at {} s",
            summary.exploration_time_s, last.time_s
        ));
    }
    Ok(())
}

/// The buildings' own starts [`check_import`] found: by building index and robot radius (bits).
pub type Starts = std::collections::BTreeMap<(usize, u64), Result<([f64; 3], String), String>>;

/// How far a stored curve's last explored fraction may be from its summary's (the store keeps
/// five decimals).
const CURVE_FRACTION_TOLERANCE: f64 = 1e-5;
/// How far a stored curve's last time may be from its summary's exploration time (the store
/// keeps tenths of a second).
const CURVE_TIME_TOLERANCE_S: f64 = 0.1;

/// A run line as a store's row, checked as a store's row is read.
fn run_of(r: RunLine) -> Result<StoredResult, String> {
    let row = StoredResult {
        job_id: r.job_id,
        grid: r.grid,
        building: r.building,
        building_hash: r.building_hash,
        strategy: r.strategy,
        label: r.label,
        seed: 0,
        settings: floorcast_worker::Settings::default(),
        status: JobStatus::Ok,
        error: None,
        summary: None,
        progress: None,
        worker: r.worker,
        wall_time_s: r.wall_time_s,
        floorcast_version: r.floorcast_version,
        stderr_tail: None,
    };
    decode_exported(row, r.seed, &r.settings, &r.summary, r.progress)
}

#[cfg(test)]
mod tests {
    use super::*;
    use floorcast_stats::metric::time_to_fraction;

    fn curve(points: &[(f64, f64)]) -> Vec<Sample> {
        points
            .iter()
            .map(|&(t, f)| Sample {
                time_s: t,
                explored_area_m2: f * 100.0,
                explored_fraction: f,
            })
            .collect()
    }

    /// The thinned curve keeps the first sample, the last, and the time to every whole percent
    /// and every tenth of a percent from 95 %, whatever the sampling.
    #[test]
    fn thinning_keeps_the_times_to_each_level() {
        // A curve sampled every second, rising unevenly, flat at the end.
        let full: Vec<Sample> = curve(
            &(0..3000)
                .map(|i| {
                    let t = i as f64;
                    (t, (1.0 - (-t / 400.0).exp()).min(0.9987))
                })
                .collect::<Vec<_>>(),
        );
        let thin = thin(&full);
        assert!(thin.len() < 160, "{} samples kept", thin.len());
        assert_eq!(thin.first(), full.first());
        assert_eq!(thin.last(), full.last());
        for level in (1..95)
            .map(|p| p as f64 / 100.0)
            .chain((950..=1000).map(|m| m as f64 / 1000.0))
        {
            assert_eq!(
                time_to_fraction(&thin, level),
                time_to_fraction(&full, level),
                "level {level}"
            );
        }
    }
}
