//! The messages coordinator and remote workers exchange, as versioned, validated types.
//!
//! Every message is a JSON object `{"format": "floorcast-wire", "version": 2, "kind": …, "body":
//! …}`. [`decode`] checks the envelope before it trusts the body, so a foreign or malformed
//! message becomes a [`WireError`] that names what was wrong (and is logged and dropped by the
//! transport), never a panic. Nothing here knows zenoh: `floorcast_coordinator::net` moves these bytes.
//!
//! A job names its building by content hash; a worker fetches each building once
//! ([`BuildingRequest`] -> [`WireBuilding`]) and keeps it, so it needs no files. Floats cross
//! bit-exactly (serde_json's `float_roundtrip`), and the worker checks the building's content
//! hash before it runs anything.

use base64::Engine as _;
use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};
use sim_core::{Bitmap, Building, Door, Geometry, GridFrame, Polygon, Pose, Room, Vec2};

use crate::{RunSummary, Settings, FLOORCAST_VERSION, SUMMARY_VERSION};

/// The value of every message's `format` key.
pub const WIRE_FORMAT: &str = "floorcast-wire";
/// The protocol version this build speaks.
pub const WIRE_VERSION: u32 = 2;

#[derive(Debug, thiserror::Error, PartialEq)]
pub enum WireError {
    #[error("not a floorcast message: {0}")]
    NotFloorcast(String),
    #[error(
        "floorcast wire protocol version {found}, this floorcast speaks version {WIRE_VERSION}"
    )]
    Version { found: u64 },
    #[error("expected a '{expected}' message, got '{found}'")]
    Kind { expected: String, found: String },
    #[error("malformed '{kind}' message: {message}")]
    Body { kind: String, message: String },
}

/// A message type and its `kind` tag.
pub trait Message: Serialize + DeserializeOwned {
    const KIND: &'static str;
}

#[derive(Serialize)]
struct EnvelopeOut<'a, T> {
    format: &'static str,
    version: u32,
    kind: &'static str,
    body: &'a T,
}

/// Encodes a message with its envelope.
pub fn encode<T: Message>(msg: &T) -> Vec<u8> {
    serde_json::to_vec(&EnvelopeOut {
        format: WIRE_FORMAT,
        version: WIRE_VERSION,
        kind: T::KIND,
        body: msg,
    })
    .expect("wire messages serialise")
}

/// Decodes and validates a message of type `T`.
pub fn decode<T: Message>(bytes: &[u8]) -> Result<T, WireError> {
    let v: serde_json::Value = serde_json::from_slice(bytes)
        .map_err(|e| WireError::NotFloorcast(format!("not JSON ({e}; {} bytes)", bytes.len())))?;
    let Some(obj) = v.as_object() else {
        return Err(WireError::NotFloorcast("not a JSON object".into()));
    };
    match obj.get("format").and_then(|f| f.as_str()) {
        Some(WIRE_FORMAT) => {}
        other => {
            return Err(WireError::NotFloorcast(format!(
                "format is {other:?}, expected \"{WIRE_FORMAT}\""
            )))
        }
    }
    match obj.get("version").and_then(|f| f.as_u64()) {
        Some(v) if v == WIRE_VERSION as u64 => {}
        Some(found) => return Err(WireError::Version { found }),
        None => return Err(WireError::NotFloorcast("no numeric 'version'".into())),
    }
    let kind = obj.get("kind").and_then(|k| k.as_str()).unwrap_or("");
    if kind != T::KIND {
        return Err(WireError::Kind {
            expected: T::KIND.into(),
            found: kind.into(),
        });
    }
    let body = obj.get("body").cloned().unwrap_or(serde_json::Value::Null);
    serde_json::from_value(body).map_err(|e| WireError::Body {
        kind: T::KIND.into(),
        message: e.to_string(),
    })
}

/// A worker asks for a job (`ctl/next`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Hello {
    pub worker: String,
    pub host: String,
    pub floorcast_version: String,
    /// The run-summary format the worker writes ([`SUMMARY_VERSION`]).
    pub result_format: u32,
    /// The worker's bench signature ([`crate::bench_signature`]).
    pub bench: String,
}
impl Message for Hello {
    const KIND: &'static str = "hello";
}

impl Hello {
    pub fn this_build(worker: &str, host: &str) -> Self {
        Self {
            worker: worker.into(),
            host: host.into(),
            floorcast_version: FLOORCAST_VERSION.into(),
            result_format: SUMMARY_VERSION,
            bench: crate::bench_signature().into(),
        }
    }

    /// Whether this coordinator can take results from the worker: the same floorcast version
    /// and result format (job ids and summaries depend on both), and the same bench signature
    /// (the worker computes as the coordinator does).
    pub fn compatible(&self) -> Result<(), String> {
        if self.floorcast_version != FLOORCAST_VERSION || self.result_format != SUMMARY_VERSION {
            return Err(format!(
                "worker '{}' runs floorcast {} (result format {}), the coordinator floorcast {} (result format {}); install the same floorcast version on every machine",
                self.worker, self.floorcast_version, self.result_format, FLOORCAST_VERSION, SUMMARY_VERSION
            ));
        }
        let own = crate::bench_signature();
        if self.bench != own {
            return Err(format!(
                "worker '{}' computes differently: its bench signature is {}, the coordinator's {} (another build, compiler flags or platform); its runs would not match this grid's: build floorcast the same way on every machine",
                self.worker,
                clip_signature(&self.bench),
                clip_signature(own)
            ));
        }
        Ok(())
    }
}

/// A signature as shown in a message: its first 16 characters (a foreign one may be anything).
fn clip_signature(s: &str) -> String {
    let shown: String = s
        .chars()
        .take(16)
        .map(|c| if c.is_control() { '?' } else { c })
        .collect();
    if s.chars().count() > 16 {
        format!("{shown}…")
    } else {
        shown
    }
}

/// The coordinator's answer to [`Hello`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum NextReply {
    /// Run this job; renew the lease before `lease_s` seconds pass.
    Job { job: Box<WireJob>, lease_s: f64 },
    /// Nothing to hand out now (all jobs leased); ask again after `retry_ms`.
    Wait { retry_ms: u64 },
    /// The grid is complete: leave.
    Done,
    /// This worker cannot take part (e.g. another floorcast version).
    Refused { reason: String },
}
impl Message for NextReply {
    const KIND: &'static str = "next-reply";
}

/// One job, with everything needed to run it (the building by its content hash).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WireJob {
    pub job_id: String,
    pub grid: String,
    pub building_name: String,
    pub building_hash: String,
    pub strategy: String,
    pub label: String,
    pub seed: u64,
    pub settings: Settings,
    /// The start pose the grid sets, bit-exact (absent: the building's own start).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub start: Option<WireStart>,
    /// An external strategy's program, with its files (absent: the built-in `strategy`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub program: Option<WireProgram>,
}

/// An external strategy's program as it travels: its identity and its files' contents, which
/// the worker writes to a directory of its own and checks against `files_sha256` before it
/// runs anything.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WireProgram {
    pub command: Vec<String>,
    #[serde(default)]
    pub files: Vec<String>,
    pub files_sha256: String,
    pub timeout_s: f64,
    /// The strategy's own parameters (sent to it in the run message).
    #[serde(default, skip_serializing_if = "serde_json::Map::is_empty")]
    pub params: serde_json::Map<String, serde_json::Value>,
    /// Each file's name as written (relative to the grid file) and its bytes in base64.
    pub contents: Vec<(String, String)>,
}

impl WireProgram {
    /// The program with its files (read when the grid was planned).
    pub fn new(p: &crate::StrategyProgram, contents: &[(String, Vec<u8>)]) -> Self {
        let b64 = base64::engine::general_purpose::STANDARD;
        Self {
            command: p.command.clone(),
            files: p.files.clone(),
            files_sha256: p.files_sha256.clone(),
            timeout_s: p.timeout_s,
            params: p.params.clone(),
            contents: contents
                .iter()
                .map(|(n, b)| (n.clone(), b64.encode(b)))
                .collect(),
        }
    }

    /// Writes the files under `root` and returns the program to run, checked by hash.
    pub fn materialize(&self, root: &std::path::Path) -> Result<crate::StrategyProgram, String> {
        let b64 = base64::engine::general_purpose::STANDARD;
        if self.contents.len() > crate::external::MAX_PROGRAM_FILES {
            return Err(format!("the program has {} files", self.contents.len()));
        }
        let contents = self
            .contents
            .iter()
            .map(|(n, b)| {
                b64.decode(b)
                    .map(|bytes| (n.clone(), bytes))
                    .map_err(|e| format!("file {n} is not base64: {e}"))
            })
            .collect::<Result<Vec<_>, _>>()?;
        crate::StrategyProgram::materialize(
            self.command.clone(),
            self.files.clone(),
            &contents,
            &self.files_sha256,
            self.timeout_s,
            root,
        )?
        .with_params(self.params.clone())
    }
}

/// A start pose set by the grid.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WireStart {
    /// `[x_m, y_m, theta_rad]`.
    pub pose: [f64; 3],
    /// "random" or "grid".
    pub source: String,
}

/// A worker returns what a job gave (`ctl/submit/<job_id>`); the coordinator makes the store's
/// row from its own plan and this report, after [`check_report`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Submission {
    pub worker: String,
    pub job_id: String,
    pub report: JobReport,
}

/// The most bytes of an external strategy's stderr a report carries and the store keeps: its
/// end ([`crate::text::tail`]).
pub const MAX_STDERR_TAIL: usize = 64 * 1024;

/// What running a job gave: its outcome and the wall time it took.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct JobReport {
    /// Wall-clock seconds (the only part that differs between identical runs).
    pub wall_time_s: f64,
    pub outcome: JobOutcome,
    /// A failed job's external strategy's stderr, its last [`MAX_STDERR_TAIL`] bytes at most
    /// (a successful job's is not sent).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stderr_tail: Option<String>,
}

/// A job's outcome: its run record and progress, or the error that stopped it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "status", rename_all = "snake_case", deny_unknown_fields)]
pub enum JobOutcome {
    Ok {
        summary: Box<RunSummary>,
        /// `[time_s, explored_area_m2, explored_fraction]` samples over the run.
        progress: Vec<[f64; 3]>,
    },
    Failed {
        error: String,
    },
}

impl JobReport {
    /// A job that could not run (or failed), and why.
    pub fn failed(error: impl Into<String>) -> Self {
        Self {
            wall_time_s: 0.0,
            outcome: JobOutcome::Failed {
                error: error.into(),
            },
            stderr_tail: None,
        }
    }

    /// Whether the job ran to its end or failed.
    pub fn status(&self) -> JobStatus {
        match self.outcome {
            JobOutcome::Ok { .. } => JobStatus::Ok,
            JobOutcome::Failed { .. } => JobStatus::Failed,
        }
    }
}

/// A job's status: it ran to its end (its record holds the run), or it failed (its record says
/// why). Stored as `ok` or `failed`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum JobStatus {
    Ok,
    Failed,
}

impl JobStatus {
    /// The word the store and the CSV export write.
    pub fn as_str(self) -> &'static str {
        match self {
            JobStatus::Ok => "ok",
            JobStatus::Failed => "failed",
        }
    }

    /// The status of a stored word (`None`: not a status).
    pub fn parse(word: &str) -> Option<JobStatus> {
        match word {
            "ok" => Some(JobStatus::Ok),
            "failed" => Some(JobStatus::Failed),
            _ => None,
        }
    }

    pub fn is_ok(self) -> bool {
        self == JobStatus::Ok
    }
}

impl std::fmt::Display for JobStatus {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.as_str())
    }
}

/// Checks that a submitted report is what `job` can give: a run record of the job's building,
/// strategy, seed, settings, start and this floorcast version, with finite numbers, or a
/// failure that says why. The error names what differs.
pub fn check_report(report: &JobReport, job: &WireJob) -> Result<(), String> {
    if !(report.wall_time_s.is_finite() && report.wall_time_s >= 0.0) {
        return Err(format!("wall_time_s is {}", report.wall_time_s));
    }
    // The tail and the line saying what was cut before it.
    if let Some(t) = &report.stderr_tail {
        if t.len() > MAX_STDERR_TAIL + 100 {
            return Err(format!(
                "stderr_tail holds {} bytes, at most {MAX_STDERR_TAIL} are sent",
                t.len()
            ));
        }
    }
    let (summary, progress) = match &report.outcome {
        JobOutcome::Failed { error } if error.trim().is_empty() => {
            return Err("a failure without an error message".into())
        }
        JobOutcome::Failed { .. } => return Ok(()),
        JobOutcome::Ok { summary, progress } => (summary, progress),
    };
    let differs = |what: &str, got: &dyn std::fmt::Debug, want: &dyn std::fmt::Debug| {
        Err(format!(
            "the summary's {what} is {got:?}, the grid's job has {want:?}"
        ))
    };
    if summary.format != crate::SUMMARY_FORMAT || summary.version != SUMMARY_VERSION {
        return differs(
            "format",
            &(&summary.format, summary.version),
            &(crate::SUMMARY_FORMAT, SUMMARY_VERSION),
        );
    }
    // Made by this floorcast, or by an earlier one whose runs of this strategy are this one's.
    if !crate::runs_as_this_build(&summary.strategy, &summary.floorcast_version) {
        return differs(
            "floorcast_version",
            &summary.floorcast_version,
            &format!(
                "{} to {FLOORCAST_VERSION}",
                crate::runs_version(&summary.strategy)
            ),
        );
    }
    if summary.building_hash != job.building_hash {
        return differs("building_hash", &summary.building_hash, &job.building_hash);
    }
    if summary.strategy != job.strategy {
        return differs("strategy", &summary.strategy, &job.strategy);
    }
    if summary.seed != job.seed {
        return differs("seed", &summary.seed, &job.seed);
    }
    if summary.settings != job.settings {
        return Err("the summary's settings differ from the grid's".into());
    }
    if let Some(planned) = &job.start {
        if summary.start.map(f64::to_bits) != planned.pose.map(f64::to_bits)
            || summary.start_source != planned.source
        {
            return Err(format!(
                "the run started at {:?} ({}), the grid's job at {:?} ({})",
                summary.start, summary.start_source, planned.pose, planned.source
            ));
        }
    }
    summary.check().map_err(|e| format!("the summary's {e}"))?;
    if let Some(p) = progress.iter().find(|p| p.iter().any(|v| !v.is_finite())) {
        return Err(format!("a progress sample is {p:?}"));
    }
    Ok(())
}
impl Message for Submission {
    const KIND: &'static str = "submission";
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum SubmitReply {
    /// Stored durably: the worker may forget it.
    Stored,
    /// This job was already stored (by this worker earlier or by another): forget it.
    Duplicate,
    /// Not a result this grid accepts; do not send it again.
    Rejected { reason: String },
}
impl Message for SubmitReply {
    const KIND: &'static str = "submit-reply";
}

/// A worker asks for a building it does not have (`ctl/building/<hash>`); the reply is the
/// [`WireBuilding`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BuildingRequest {
    pub worker: String,
}
impl Message for BuildingRequest {
    const KIND: &'static str = "building-request";
}

impl Message for WireBuilding {
    const KIND: &'static str = "building";
}

/// A worker renews its lease on a running job (`ctl/renew/<job_id>`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Renewal {
    pub worker: String,
}
impl Message for Renewal {
    const KIND: &'static str = "renewal";
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum RenewReply {
    Renewed,
    /// The job is no longer leased to this worker (it was requeued or is stored).
    NotLeased,
}
impl Message for RenewReply {
    const KIND: &'static str = "renew-reply";
}

/// A building as it travels inside a job: exact, with rooms, doors and start.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WireBuilding {
    pub name: String,
    pub geometry: WireGeometry,
    pub rooms: Vec<WireRoom>,
    pub doors: Vec<WireDoor>,
    /// `[x_m, y_m, theta_rad]`.
    pub start: Option<[f64; 3]>,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum WireGeometry {
    Raster {
        origin_m: [f64; 2],
        resolution_m: f64,
        width: u32,
        height: u32,
        /// Solid cells, one bit each in row-major order (bit `i % 8` of byte `i / 8`), base64.
        solid_bits: String,
    },
    Vector {
        outline: Vec<[f64; 2]>,
        solids: Vec<Vec<[f64; 2]>>,
    },
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WireRoom {
    pub id: u32,
    pub kind: String,
    pub polygon: Vec<[f64; 2]>,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WireDoor {
    pub a: [f64; 2],
    pub b: [f64; 2],
    pub rooms: [Option<u32>; 2],
}

fn pts(p: &Polygon) -> Vec<[f64; 2]> {
    p.vertices.iter().map(|v| [v.x, v.y]).collect()
}
fn poly(v: &[[f64; 2]]) -> Polygon {
    Polygon {
        vertices: v.iter().map(|p| Vec2::new(p[0], p[1])).collect(),
    }
}

impl WireBuilding {
    pub fn from_building(b: &Building) -> Self {
        let geometry = match &b.geometry {
            Geometry::Raster { solid } => {
                let mut bits = vec![0u8; solid.data.len().div_ceil(8)];
                for (i, &s) in solid.data.iter().enumerate() {
                    bits[i / 8] |= (s as u8) << (i % 8);
                }
                WireGeometry::Raster {
                    origin_m: [solid.frame.origin_m.x, solid.frame.origin_m.y],
                    resolution_m: solid.frame.resolution_m,
                    width: solid.frame.width,
                    height: solid.frame.height,
                    solid_bits: base64::engine::general_purpose::STANDARD.encode(bits),
                }
            }
            Geometry::Vector { outline, solids } => WireGeometry::Vector {
                outline: pts(outline),
                solids: solids.iter().map(pts).collect(),
            },
        };
        Self {
            name: b.name.clone(),
            geometry,
            rooms: b
                .rooms
                .iter()
                .map(|r| WireRoom {
                    id: r.id,
                    kind: r.kind.clone(),
                    polygon: pts(&r.polygon),
                })
                .collect(),
            doors: b
                .doors
                .iter()
                .map(|d| WireDoor {
                    a: [d.a.x, d.a.y],
                    b: [d.b.x, d.b.y],
                    rooms: d.rooms,
                })
                .collect(),
            start: b.start.map(|p| [p.x_m, p.y_m, p.theta_rad]),
        }
    }

    /// Rebuilds the building and checks it against `expected_hash`.
    pub fn to_building(&self, expected_hash: &str) -> Result<Building, String> {
        let geometry = match &self.geometry {
            WireGeometry::Raster {
                origin_m,
                resolution_m,
                width,
                height,
                solid_bits,
            } => {
                let n = *width as usize * *height as usize;
                if !(resolution_m.is_finite() && *resolution_m > 0.0) || n == 0 {
                    return Err(format!(
                        "raster {width}x{height} at {resolution_m} m per cell"
                    ));
                }
                let bits = base64::engine::general_purpose::STANDARD
                    .decode(solid_bits)
                    .map_err(|e| format!("solid_bits: {e}"))?;
                if bits.len() != n.div_ceil(8) {
                    return Err(format!(
                        "solid_bits holds {} bytes, a {width}x{height} raster needs {}",
                        bits.len(),
                        n.div_ceil(8)
                    ));
                }
                let frame = GridFrame::new(
                    Vec2::new(origin_m[0], origin_m[1]),
                    *resolution_m,
                    *width,
                    *height,
                );
                let data = (0..n).map(|i| bits[i / 8] >> (i % 8) & 1 == 1).collect();
                Geometry::Raster {
                    solid: Bitmap { frame, data },
                }
            }
            WireGeometry::Vector { outline, solids } => Geometry::Vector {
                outline: poly(outline),
                solids: solids.iter().map(|s| poly(s)).collect(),
            },
        };
        let b = Building {
            name: self.name.clone(),
            geometry,
            rooms: self
                .rooms
                .iter()
                .map(|r| Room {
                    id: r.id,
                    kind: r.kind.clone(),
                    polygon: poly(&r.polygon),
                })
                .collect(),
            doors: self
                .doors
                .iter()
                .map(|d| Door {
                    a: Vec2::new(d.a[0], d.a[1]),
                    b: Vec2::new(d.b[0], d.b[1]),
                    rooms: d.rooms,
                })
                .collect(),
            start: self.start.map(|s| Pose::new(s[0], s[1], s[2])),
        };
        let hash = b.content_hash();
        if hash != expected_hash {
            return Err(format!(
                "building '{}' arrived with content hash {hash}, the job says {expected_hash}",
                self.name
            ));
        }
        Ok(b)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn messages_round_trip_and_foreign_ones_are_refused() {
        let h = Hello::this_build("w1", "host");
        assert_eq!(decode::<Hello>(&encode(&h)).unwrap(), h);
        assert!(h.compatible().is_ok());
        let r = NextReply::Wait { retry_ms: 50 };
        assert_eq!(decode::<NextReply>(&encode(&r)).unwrap(), r);

        assert!(matches!(
            decode::<Hello>(b"garbage"),
            Err(WireError::NotFloorcast(_))
        ));
        assert!(matches!(
            decode::<Hello>(br#"{"format":"other","version":1}"#),
            Err(WireError::NotFloorcast(_))
        ));
        assert_eq!(
            decode::<Hello>(br#"{"format":"floorcast-wire","version":99,"kind":"hello"}"#),
            Err(WireError::Version { found: 99 })
        );
        assert!(matches!(
            decode::<Hello>(&encode(&r)),
            Err(WireError::Kind { .. })
        ));
        let extra = br#"{"format":"floorcast-wire","version":2,"kind":"hello","body":{"worker":"w","host":"h","floorcast_version":"x","result_format":1,"bench":"b","evil":true}}"#;
        assert!(matches!(
            decode::<Hello>(extra),
            Err(WireError::Body { .. })
        ));
        // A typed outcome crosses as it is; one of another status, or with a field too many,
        // is refused.
        let sub = Submission {
            worker: "w".into(),
            job_id: "j".into(),
            report: JobReport::failed("no start pose"),
        };
        assert_eq!(decode::<Submission>(&encode(&sub)).unwrap(), sub);
        for body in [
            r#"{"worker":"w","job_id":"j","report":{"wall_time_s":1.0,"outcome":{"status":"done","error":"x"}}}"#,
            r#"{"worker":"w","job_id":"j","report":{"wall_time_s":1.0,"outcome":{"status":"failed","error":"x","extra":1}}}"#,
            r#"{"worker":"w","job_id":"j","report":{"wall_time_s":1.0,"outcome":{"status":"ok","summary":{},"progress":[]}}}"#,
        ] {
            let msg = format!(
                r#"{{"format":"floorcast-wire","version":2,"kind":"submission","body":{body}}}"#
            );
            assert!(
                matches!(
                    decode::<Submission>(msg.as_bytes()),
                    Err(WireError::Body { .. })
                ),
                "{body}"
            );
        }
    }

    #[test]
    fn another_version_is_incompatible() {
        let mut h = Hello::this_build("w1", "host");
        h.floorcast_version = "0.0.0-other".into();
        let e = h.compatible().unwrap_err();
        assert!(e.contains("0.0.0-other") && e.contains("same floorcast version"));
    }

    #[test]
    fn buildings_cross_bit_exactly() {
        let b = crate::small_building();
        let hash = b.content_hash();
        let wire = WireBuilding::from_building(&b);
        let back: WireBuilding =
            serde_json::from_slice(&serde_json::to_vec(&wire).unwrap()).unwrap();
        assert_eq!(back.to_building(&hash).unwrap(), b);
        assert!(back.to_building("0000").is_err());

        // A raster building (odd size so the last byte is partial).
        let frame = GridFrame::new(Vec2::new(-1.234_567_891, 0.1), 0.05, 13, 7);
        let data = (0..13 * 7).map(|i| i % 3 == 0).collect();
        let r = Building {
            name: "r".into(),
            geometry: Geometry::Raster {
                solid: Bitmap { frame, data },
            },
            rooms: vec![],
            doors: vec![],
            start: Some(Pose::new(0.1, 0.2, 0.3)),
        };
        let wire = WireBuilding::from_building(&r);
        let back: WireBuilding =
            serde_json::from_slice(&serde_json::to_vec(&wire).unwrap()).unwrap();
        assert_eq!(back.to_building(&r.content_hash()).unwrap(), r);
    }
}
