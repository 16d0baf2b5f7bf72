//! The `lenspath` binary: the command line of [`lenspath_cli`].

use std::process::ExitCode;

fn main() -> ExitCode {
    ExitCode::from(lenspath_cli::run(std::env::args_os()))
}
