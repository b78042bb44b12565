//! Small helpers for writing outputs and showing progress.

use std::io::IsTerminal;
use std::path::Path;

use anyhow::{Context, Result};
use indicatif::{ProgressBar, ProgressStyle};

/// Creates `dir` (and parents), with a message naming it on failure.
/// The picture format of a run's maps (`--picture`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Picture {
    Png,
    Svg,
}

impl Picture {
    /// The file extension, which also chooses the encoder.
    pub fn extension(self) -> &'static str {
        match self {
            Picture::Png => "png",
            Picture::Svg => "svg",
        }
    }
}

pub fn create_dir(dir: &Path) -> Result<()> {
    std::fs::create_dir_all(dir)
        .with_context(|| format!("cannot create directory {}", dir.display()))
}

/// Writes a text file, naming it on failure.
pub fn write_text(path: &Path, text: &str) -> Result<()> {
    std::fs::write(path, text).with_context(|| format!("cannot write {}", path.display()))
}

/// A progress bar on stderr, hidden when `quiet` or when stderr is not a terminal.
pub fn progress_bar(len: u64, quiet: bool, template: &str) -> ProgressBar {
    if quiet || !std::io::stderr().is_terminal() {
        return ProgressBar::hidden();
    }
    let pb = ProgressBar::new(len);
    if let Ok(style) = ProgressStyle::with_template(template) {
        pb.set_style(style.progress_chars("=> "));
    }
    pb
}

/// Parses "x,y,theta" (metres, metres, degrees).
pub fn parse_pose(s: &str) -> Result<sim_core::Pose, String> {
    let parts: Vec<&str> = s.split(',').map(str::trim).collect();
    if parts.len() != 3 {
        return Err(format!(
            "expected x,y,theta (metres, metres, degrees), got '{s}'"
        ));
    }
    let mut v = [0.0; 3];
    for (i, p) in parts.iter().enumerate() {
        v[i] = p
            .parse::<f64>()
            .ok()
            .filter(|x| x.is_finite())
            .ok_or_else(|| format!("'{p}' in '{s}' is not a finite number (expected x,y,theta)"))?;
    }
    Ok(sim_core::Pose::new(v[0], v[1], v[2].to_radians()))
}

/// Ctrl-C ends floorcast at once (exit code 130) and every strategy program with everything it
/// started: each runs in a process group of its own, which the terminal's signal does not reach.
pub fn stop_programs_on_ctrl_c() {
    let _ = ctrlc::set_handler(|| {
        floorcast_worker::external::kill_all_programs();
        std::process::exit(130);
    });
}

/// Writes one line to stdout. A closed pipe (`floorcast ... | head`) ends the program quietly
/// with exit code 0, as `head`'s reader wanted no more; any other failed write (a full disk) is
/// an error: one line on stderr and exit code 2, never a silently cut output.
pub fn say_fmt(args: std::fmt::Arguments<'_>, newline: bool) {
    use std::io::Write;
    let mut out = std::io::stdout().lock();
    let r = if newline {
        writeln!(out, "{args}")
    } else {
        write!(out, "{args}")
    };
    if let Err(e) = r.and_then(|_| out.flush()) {
        stdout_failed(&e);
    }
}

/// Ends the program after a failed write to stdout: quietly (exit code 0) on a closed pipe, else
/// with one line naming the problem and exit code 2.
pub fn stdout_failed(e: &std::io::Error) -> ! {
    if e.kind() == std::io::ErrorKind::BrokenPipe {
        std::process::exit(0);
    }
    eprintln!("error: cannot write to stdout ({e}); free space on its device or send the output elsewhere");
    std::process::exit(2);
}

/// `println!` that survives a closed pipe and fails on a full disk.
macro_rules! say {
    ($($t:tt)*) => { crate::output::say_fmt(format_args!($($t)*), true) };
}

/// `print!` that survives a closed pipe and fails on a full disk.
macro_rules! say_raw {
    ($($t:tt)*) => { crate::output::say_fmt(format_args!($($t)*), false) };
}
