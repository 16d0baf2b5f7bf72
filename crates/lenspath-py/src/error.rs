//! Library errors as Python exceptions: `ValueError` for bad arguments,
//! `lenspath.SceneError` for broken scene files, `lenspath.LensError` for
//! broken lens tables, `OSError` for I/O; one argument, since a library
//! error says what kind of file it is about.

use lenspath::names::Named;
use lenspath::{Error, FileKind};
use pyo3::create_exception;
use pyo3::exceptions::{PyException, PyOSError, PyValueError};
use pyo3::prelude::*;

create_exception!(
    lenspath,
    LenspathError,
    PyException,
    "Base class of lenspath's own errors."
);
create_exception!(
    lenspath,
    SceneError,
    LenspathError,
    "A scene file is broken or inconsistent."
);
create_exception!(lenspath, LensError, LenspathError, "A lens table is broken.");

/// The library value a keyword names, if it names one ([`Named::parse`]:
/// a `ValueError` listing the names otherwise).
pub(crate) fn named<T: Named>(name: Option<&str>) -> PyResult<Option<T>> {
    name.map(T::parse).transpose().map_err(to_py)
}

/// A library error as the Python exception users expect: the error says
/// what kind of file a parse failure is about.
pub(crate) fn to_py(error: Error) -> PyErr {
    let message = error.to_string();
    match error {
        Error::InvalidArgument(_) => PyValueError::new_err(message),
        Error::InvalidScene(_) => SceneError::new_err(message),
        Error::Parse { kind, .. } => match kind {
            FileKind::Scene => SceneError::new_err(message),
            FileKind::Lens => LensError::new_err(message),
            FileKind::Image | FileKind::Checkpoint | FileKind::Other => PyValueError::new_err(message),
        },
        Error::Io { source, .. } => PyOSError::new_err((source.raw_os_error().unwrap_or(0), message)),
    }
}

pub(crate) fn value_error(message: impl Into<String>) -> PyErr {
    PyValueError::new_err(message.into())
}

/// Warns that something is deprecated (a `DeprecationWarning` naming what replaces it).
pub(crate) fn deprecated(py: Python<'_>, message: &str) -> PyResult<()> {
    let category = py.get_type::<pyo3::exceptions::PyDeprecationWarning>();
    PyErr::warn(
        py,
        &category,
        &std::ffi::CString::new(message).expect("no NUL in the message"),
        2,
    )
}

/// An argument of `function` given by its name, `new`, or by its deprecated
/// old name, `old` (with a warning naming the new one; `same` says what the
/// old one meant), never both.
pub(crate) fn renamed<T>(
    py: Python<'_>,
    function: &str,
    (new_name, new): (&str, Option<T>),
    (old_name, old): (&str, Option<T>),
    same: &str,
) -> PyResult<Option<T>> {
    match (new, old) {
        (Some(_), Some(_)) => Err(PyValueError::new_err(format!(
            "give {new_name}, not also {old_name} (its old name)"
        ))),
        (None, Some(value)) => {
            deprecated(
                py,
                &format!("{function}({old_name}=...) is deprecated; use {new_name}=... ({same})"),
            )?;
            Ok(Some(value))
        }
        (new, None) => Ok(new),
    }
}

/// Runs library code `f`, turning a panic (a bug in lenspath) into
/// `lenspath.LenspathError` saying so: left alone, pyo3 raises
/// `PanicException`, a `BaseException` that `except Exception` misses, and
/// a panic on a worker thread would never reach Python at all. The error
/// is made lazily, so `f` may run without the GIL.
pub(crate) fn guarded<T>(f: impl FnOnce() -> T) -> PyResult<T> {
    std::panic::catch_unwind(std::panic::AssertUnwindSafe(f)).map_err(|payload| {
        let what = payload
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| payload.downcast_ref::<String>().cloned())
            .unwrap_or_else(|| "a panic without a message".into());
        LenspathError::new_err(format!(
            "internal error, a bug in lenspath (please report it with the call that raised it): {what}"
        ))
    })
}

/// An integer argument as the type the library takes, or a `ValueError`
/// naming it (pyo3's own `OverflowError` for -1 names no argument).
pub(crate) fn whole_number<T: TryFrom<i64>>(name: &str, value: Option<i64>) -> PyResult<Option<T>> {
    value
        .map(|v| T::try_from(v).map_err(|_| value_error(format!("{name} must be a whole number from 0, got {v}"))))
        .transpose()
}
