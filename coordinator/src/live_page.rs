//! The live view's page (`GET /` of `run --http`): a [`Status`] as one self-contained HTML page
//! (no script, no file fetched: it reloads itself every few seconds), with a progress bar, the
//! workers, a sequential grid's LLR paths between their bounds, the failures and the last log
//! lines. Every text that came from a worker or a program is escaped.

use std::fmt::Write;

use crate::live::{Status, TestStatus};

/// Seconds between the page's reloads.
pub const REFRESH_S: u32 = 5;

/// The bar's colours: stored, failed, running, left.
pub const DONE_RGB: [u8; 3] = [0x2e, 0x7d, 0x32];
pub const FAILED_RGB: [u8; 3] = [0xc6, 0x28, 0x28];
pub const RUNNING_RGB: [u8; 3] = [0xf9, 0xa8, 0x25];
const LEFT_RGB: [u8; 3] = [0xe0, 0xe0, 0xe0];

fn hex([r, g, b]: [u8; 3]) -> String {
    format!("#{r:02x}{g:02x}{b:02x}")
}

/// `s` safe inside HTML text and attribute values.
pub fn escape(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&#39;"),
            c => out.push(c),
        }
    }
    out
}

/// Seconds as `1 h 02 min`, `3 min 07 s` or `12 s`.
pub fn duration(s: f64) -> String {
    let s = s.max(0.0).round() as u64;
    match s {
        0..60 => format!("{s} s"),
        60..3600 => format!("{} min {:02} s", s / 60, s % 60),
        _ => format!("{} h {:02} min", s / 3600, s % 3600 / 60),
    }
}

const STYLE: &str = "body{font-family:sans-serif;margin:1.5em;color:#222}\
table{border-collapse:collapse;margin:.5em 0 1.5em}td,th{border:1px solid #ccc;padding:.25em .6em;text-align:left}\
th{background:#f3f3f3}.bar{display:flex;height:28px;width:100%;max-width:900px;border:1px solid #999}\
.bar div{height:100%}pre{background:#f6f6f6;padding:.5em;overflow-x:auto}.muted{color:#777}";

/// The whole page.
pub fn page(s: &Status) -> String {
    let mut h = String::new();
    let _ = write!(
        h,
        "<!DOCTYPE html><html><head><meta charset=\"utf-8\"><meta http-equiv=\"refresh\" content=\"{REFRESH_S}\">\
         <title>floorcast: {grid} ({state})</title><style>{STYLE}</style></head><body>\
         <h1>Grid {grid}: {state}</h1>",
        grid = escape(&s.grid),
        state = escape(&s.state)
    );
    progress(&mut h, s);
    workers(&mut h, s);
    if !s.sequential.is_empty() {
        h.push_str("<h2>Sequential tests</h2>");
        for t in &s.sequential {
            llr_chart(&mut h, t);
        }
    }
    failures(&mut h, s);
    h.push_str("<h2>Log</h2><pre id=\"log\">");
    for l in &s.log {
        let _ = writeln!(h, "{}", escape(l));
    }
    let _ = write!(
        h,
        "</pre><p class=\"muted\">Reloads every {REFRESH_S} s. The same as JSON: <a href=\"/status.json\">status.json</a> ({} version {}).</p></body></html>",
        crate::live::STATUS_FORMAT,
        crate::live::STATUS_VERSION
    );
    h
}

fn progress(h: &mut String, s: &Status) {
    let j = &s.jobs;
    let eta = s.eta_s.map_or("not known yet".to_string(), |e| {
        format!("about {}", duration(e))
    });
    let _ = write!(
        h,
        "<p id=\"jobs\"><b>{done} of {total} jobs stored</b> ({before} before this run), {running} running, {failed} failed, {left} left. \
         Running for {elapsed}; ETA {eta}.</p><div class=\"bar\" title=\"stored / failed / running / left\">",
        done = j.done,
        total = j.total,
        before = j.stored_before,
        running = j.running,
        failed = j.failed,
        left = j.left,
        elapsed = duration(s.elapsed_s),
    );
    let total = j.total.max(1) as f64;
    let ok = j.done.saturating_sub(j.failed.min(j.done));
    for (n, rgb) in [
        (ok, DONE_RGB),
        (j.failed.min(j.done), FAILED_RGB),
        (j.running, RUNNING_RGB),
        (j.left, LEFT_RGB),
    ] {
        if n > 0 {
            let _ = write!(
                h,
                "<div style=\"width:{:.3}%;background:{}\"></div>",
                100.0 * n as f64 / total,
                hex(rgb)
            );
        }
    }
    h.push_str("</div>");
}

fn workers(h: &mut String, s: &Status) {
    let _ = write!(h, "<h2>Workers ({})</h2>", s.workers.len());
    if s.workers.is_empty() {
        h.push_str("<p class=\"muted\">None has asked for a job yet.</p>");
        return;
    }
    h.push_str("<table id=\"workers\"><tr><th>worker</th><th>kind</th><th>state</th><th>jobs stored</th><th>failed</th><th>jobs per hour</th><th>last contact</th><th>running</th></tr>");
    for w in &s.workers {
        let _ = write!(
            h,
            "<tr><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{:.1}</td><td>{} ago</td><td>{}</td></tr>",
            escape(&w.name),
            escape(&w.kind),
            if w.connected { "connected" } else { "left" },
            w.jobs_done,
            w.jobs_failed,
            w.jobs_per_hour,
            duration(w.last_contact_s),
            escape(
                &w.running
                    .iter()
                    .map(|j| format!("{} {} seed {}", j.building, j.label, j.seed))
                    .collect::<Vec<_>>()
                    .join(", ")
            )
        );
    }
    h.push_str("</table>");
}

fn failures(h: &mut String, s: &Status) {
    let _ = write!(h, "<h2>Failures ({})</h2>", s.failures_total);
    if s.failures.is_empty() {
        h.push_str("<p class=\"muted\">No job has failed in this run.</p>");
        return;
    }
    if s.failures_total > s.failures.len() {
        let _ = write!(
            h,
            "<p class=\"muted\">The last {}; <code>floorcast report RESULTS --failures</code> lists them all.</p>",
            s.failures.len()
        );
    }
    h.push_str("<table id=\"failures\"><tr><th>job</th><th>building</th><th>strategy</th><th>seed</th><th>worker</th><th>error</th></tr>");
    for f in &s.failures {
        let _ = write!(
            h,
            "<tr><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr>",
            escape(&f.job_id),
            escape(&f.building),
            escape(&f.label),
            f.seed,
            escape(&f.worker),
            escape(&f.error)
        );
    }
    h.push_str("</table>");
}

/// One label's LLR at each look (pairs across), between its bounds, as an inline SVG.
fn llr_chart(h: &mut String, t: &TestStatus) {
    const W: f64 = 480.0;
    const H: f64 = 180.0;
    const PAD: f64 = 36.0;
    let max_pairs = t.points.iter().map(|p| p.pairs).max().unwrap_or(1).max(1) as f64;
    let llrs = t.points.iter().filter_map(|p| p.llr);
    let (lo, hi) = llrs.fold((t.lower, t.upper), |(a, b), l| (a.min(l), b.max(l)));
    let span = (hi - lo).max(1e-9) * 1.1;
    let mid = (hi + lo) / 2.0;
    let x = |pairs: f64| PAD + (W - 2.0 * PAD) * pairs / max_pairs;
    let y = |llr: f64| H / 2.0 - (H - PAD) * (llr - mid) / span;
    let _ = write!(
        h,
        "<h3>{} against {}: {}</h3><svg class=\"llr\" width=\"{W}\" height=\"{H}\" viewBox=\"0 0 {W} {H}\" xmlns=\"http://www.w3.org/2000/svg\">\
         <rect x=\"0\" y=\"0\" width=\"{W}\" height=\"{H}\" fill=\"#fafafa\" stroke=\"#ccc\"/>",
        escape(&t.label),
        escape(&t.reference),
        escape(&t.decision)
    );
    for (b, name, rgb) in [(t.upper, "H1", DONE_RGB), (t.lower, "H0", FAILED_RGB)] {
        let _ = write!(
            h,
            "<line x1=\"{PAD}\" x2=\"{}\" y1=\"{yb:.1}\" y2=\"{yb:.1}\" stroke=\"{c}\" stroke-dasharray=\"6 4\"/>\
             <text x=\"{}\" y=\"{:.1}\" font-size=\"11\" fill=\"{c}\">{name} {b:.2}</text>",
            W - PAD,
            W - PAD + 2.0,
            y(b) + 4.0,
            yb = y(b),
            c = hex(rgb)
        );
    }
    let pts: Vec<String> = t
        .points
        .iter()
        .filter_map(|p| {
            p.llr
                .map(|l| format!("{:.1},{:.1}", x(p.pairs as f64), y(l)))
        })
        .collect();
    let _ = write!(
        h,
        "<polyline points=\"{}\" fill=\"none\" stroke=\"#1565c0\" stroke-width=\"2\"/>",
        pts.join(" ")
    );
    for p in pts {
        let (px, py) = p.split_once(',').unwrap_or(("0", "0"));
        let _ = write!(
            h,
            "<circle cx=\"{px}\" cy=\"{py}\" r=\"3\" fill=\"#1565c0\"/>"
        );
    }
    let _ = write!(
        h,
        "<text x=\"{PAD}\" y=\"{:.1}\" font-size=\"11\">LLR by pairs (0 to {max_pairs})</text></svg>",
        H - 6.0
    );
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::live::{FailureStatus, JobCounts, LlrPoint, WorkerStatus};

    fn status() -> Status {
        Status {
            format: crate::live::STATUS_FORMAT.into(),
            version: 1,
            grid: "g<1>".into(),
            state: "running".into(),
            started_unix_s: 0.0,
            elapsed_s: 3725.0,
            jobs: JobCounts {
                total: 10,
                done: 6,
                running: 1,
                failed: 2,
                left: 3,
                stored_before: 1,
            },
            eta_s: Some(61.0),
            workers: vec![WorkerStatus {
                name: "<script>alert(1)</script>".into(),
                kind: "remote".into(),
                connected: false,
                jobs_done: 3,
                jobs_failed: 1,
                jobs_per_hour: 12.25,
                last_contact_s: 7.0,
                running: vec![crate::live::RunningJob {
                    job_id: "job-a".into(),
                    building: "b1".into(),
                    label: "x.py".into(),
                    seed: 3,
                }],
            }],
            failures: vec![FailureStatus {
                job_id: "j".into(),
                building: "b".into(),
                label: "x.py".into(),
                seed: 4,
                worker: "w".into(),
                error: "a < b & \"c\"".into(),
            }],
            failures_total: 2,
            sequential: vec![TestStatus {
                label: "nearest".into(),
                reference: "baseline".into(),
                decision: "undecided".into(),
                lower: -2.9,
                upper: 2.9,
                points: vec![
                    LlrPoint {
                        through_seed: 5,
                        pairs: 5,
                        llr: None,
                    },
                    LlrPoint {
                        through_seed: 10,
                        pairs: 10,
                        llr: Some(1.0),
                    },
                    LlrPoint {
                        through_seed: 15,
                        pairs: 15,
                        llr: Some(2.0),
                    },
                ],
            }],
            log: vec!["worker <w> joined".into()],
        }
    }

    #[test]
    fn the_page_shows_everything_escaped() {
        let p = page(&status());
        for needle in [
            "<title>floorcast: g&lt;1&gt; (running)</title>",
            "<b>6 of 10 jobs stored</b> (1 before this run), 1 running, 2 failed, 3 left",
            "Running for 1 h 02 min; ETA about 1 min 01 s",
            "Workers (1)",
            "&lt;script&gt;alert(1)&lt;/script&gt;",
            "<td>left</td><td>3</td><td>1</td><td>12.2</td><td>7 s ago</td><td>b1 x.py seed 3</td>",
            "Failures (2)",
            "The last 1;",
            "a &lt; b &amp; &quot;c&quot;",
            "nearest against baseline: undecided",
            "worker &lt;w&gt; joined",
            "href=\"/status.json\"",
        ] {
            assert!(p.contains(needle), "'{needle}' missing:\n{p}");
        }
        assert!(!p.contains("<script>"));
        // The bar: 4 stored, 2 failed, 1 running, 3 left of 10.
        for (pct, rgb) in [
            ("40.000", DONE_RGB),
            ("20.000", FAILED_RGB),
            ("10.000", RUNNING_RGB),
        ] {
            assert!(
                p.contains(&format!("width:{pct}%;background:{}", hex(rgb))),
                "{pct}"
            );
        }
        // Two looks with an LLR: two points on the path.
        assert_eq!(p.matches("<circle ").count(), 2);
    }

    #[test]
    fn durations_read_as_people_write_them() {
        for (s, text) in [
            (0.0, "0 s"),
            (59.4, "59 s"),
            (61.0, "1 min 01 s"),
            (3599.0, "59 min 59 s"),
            (3600.0, "1 h 00 min"),
            (90061.0, "25 h 01 min"),
            (-5.0, "0 s"),
        ] {
            assert_eq!(duration(s), text, "{s}");
        }
    }
}
