//! Where the integration tests find ../shared, the third-party assets beside the repository
//! (see ../shared/ASSETS.md): the one rule the tests that read it follow, so that they all skip,
//! saying so, when it is absent, or hidden by `LENSPATH_TESTS_WITHOUT_SHARED=1` (CI's second pass,
//! which checks that the suite passes on a fresh clone without it; the pytest suite reads the
//! same switch in `tests/python/conftest.py`).

use std::path::{Path, PathBuf};

/// The environment variable that, set to 1, hides ../shared from the tests.
pub const WITHOUT_SHARED_SWITCH: &str = "LENSPATH_TESTS_WITHOUT_SHARED";

/// `path` in the repository (relative to its root).
pub fn repo(path: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..").join(path)
}

/// `path` in ../shared, or `None` (after saying on stderr why the test skips it) when the folder
/// is absent or hidden.
pub fn shared(path: &str) -> Option<PathBuf> {
    let hidden = std::env::var(WITHOUT_SHARED_SWITCH).is_ok_and(|v| v == "1");
    shared_in(&repo("../shared"), path, hidden)
}

/// [`shared`] for a given folder and switch (the rule itself, testable without the environment).
fn shared_in(folder: &Path, path: &str, hidden: bool) -> Option<PathBuf> {
    let file = folder.join(path);
    if hidden {
        eprintln!(
            "skipping: {} (../shared is hidden by {WITHOUT_SHARED_SWITCH}=1)",
            file.display()
        );
        None
    } else if file.exists() {
        Some(file)
    } else {
        eprintln!("skipping: {} not found (../shared is absent)", file.display());
        None
    }
}

#[test]
fn the_switch_hides_a_file_that_is_there() {
    let here = Path::new(env!("CARGO_MANIFEST_DIR"));
    assert_eq!(shared_in(here, "Cargo.toml", false), Some(here.join("Cargo.toml")));
    assert_eq!(shared_in(here, "Cargo.toml", true), None);
    assert_eq!(shared_in(here, "no-such-file", false), None);
}
