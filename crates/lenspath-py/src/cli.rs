//! The `lenspath` command of the Python package: the CLI crate's own code
//! ([`lenspath_cli::run`]), so `pip install` gives the same command as
//! `cargo install`.

use std::ffi::OsString;

use pyo3::prelude::*;

/// Runs the command line `argv` (the program's name first) without the GIL and returns its exit
/// code.
#[pyfunction]
pub(crate) fn run_cli(py: Python<'_>, argv: Vec<OsString>) -> u8 {
    py.detach(|| lenspath_cli::run(argv))
}
