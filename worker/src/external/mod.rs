//! External strategies: a program, in any language, that speaks floorcast's strategy protocol
//! (`docs/strategy-protocol.md`) over its stdin and stdout, one JSON object per line. One file
//! per job:
//!
//! - [`program`]: the program as a job carries it (command, files, their hash, timeout,
//!   params), its files shipped to remote workers.
//! - [`protocol`]: the protocol's messages as types, and the one check of a program's reply.
//! - [`child`]: the program's process and the threads of its pipes.
//! - [`groups`]: the programs' process groups, and the strays they leave.
//! - [`session`]: [`ExternalStrategy`], a running program asked at every decision (a `Policy`).
//! - [`check`]: the compliance checker (`floorcast strategy check`).
//! - [`temp`]: the programs' private folders, each naming its owner, and those of killed
//!   processes removed.

mod check;
mod child;
mod groups;
mod program;
pub mod protocol;
mod session;
mod temp;

pub use check::{check_program, Check};
pub use child::PYTHON_MODULE;
pub use groups::{adopt_orphans, end_strays, kill_all_programs, stopping};
pub use program::{
    check_file, check_timeout, ProgramFiles, StrategyProgram, DEFAULT_TIMEOUT_S, MAX_PARAMS_BYTES,
    MAX_PROGRAM_BYTES, MAX_PROGRAM_FILES,
};
pub use protocol::{run_message, Hello, PROTOCOL_VERSION};
pub use session::{ExternalStrategy, StrategyError, StrategyStats};
pub use temp::{
    private_temp_dir, remove_stale_temp_dirs, remove_stale_temp_dirs_in, TEMP_PREFIXES,
};

/// At most `n` bytes of `s` (a program's output, echoed in a message), its control characters
/// escaped ([`crate::text::shown`]).
fn clip(s: &str, n: usize) -> String {
    crate::text::shown(s, n)
}
