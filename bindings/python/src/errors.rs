//! The exceptions minkq raises, one per C error code (`minkq_status`), defined here where they
//! are raised: the extension creates the classes when it is loaded and the package re-exports
//! them (minkq._errors), so this lower layer imports nothing from the package above it.
//!
//! Each subclasses `MinkqError` and the built-in exception closest to its meaning, so that
//! `except ValueError` also catches bad input. pyo3's `create_exception!` takes one base only,
//! so the classes are made with `type(name, bases, namespace)`; their `__init__` and `__str__`
//! are the Rust functions below, bound as methods through `functools.partialmethod` (a builtin
//! function does not bind to an instance by itself).
use pyo3::exceptions::{PyException, PyMemoryError, PyOverflowError, PyRuntimeError, PyValueError};
use pyo3::once_cell::GILOnceCell;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple, PyType};

use minkq::sys;

/// Which built-in exception (besides MinkqError) each class also is.
#[derive(Clone, Copy)]
enum Builtin {
    None,
    Value,
    Overflow,
    Memory,
    Runtime,
}

/// The classes of the C statuses: status, class name, built-in base, docstring. The status
/// names (`status_name`) come from the library's `minkq_status_name`.
const CLASSES: [(u32, &str, Builtin, &str); 9] = [
    (
        sys::MINKQ_ERROR_INVALID_ARGUMENT,
        "InvalidArgumentError",
        Builtin::Value,
        "MINKQ_ERROR_INVALID_ARGUMENT: a bad enum, stride, flag combination, count or spec.",
    ),
    (
        sys::MINKQ_ERROR_NON_FINITE,
        "NonFiniteError",
        Builtin::Value,
        "MINKQ_ERROR_NON_FINITE: NaN or infinity in a coordinate or the radius.",
    ),
    (
        sys::MINKQ_ERROR_INDEX_OUT_OF_RANGE,
        "IndexOutOfRangeError",
        Builtin::Value,
        "MINKQ_ERROR_INDEX_OUT_OF_RANGE: a negative or too large vertex index.",
    ),
    (
        sys::MINKQ_ERROR_SIZE_OVERFLOW,
        "SizeOverflowError",
        Builtin::Overflow,
        "MINKQ_ERROR_SIZE_OVERFLOW: a count over 2**31 - 2, or one whose byte size overflows.",
    ),
    (
        sys::MINKQ_ERROR_CAPACITY,
        "CapacityError",
        Builtin::None,
        "MINKQ_ERROR_CAPACITY: the output array holds fewer pairs than the query found.\n\n\
         ``needed`` is the exact number of pairs; nothing was written past the array.",
    ),
    (
        sys::MINKQ_ERROR_UNSUPPORTED,
        "UnsupportedError",
        Builtin::None,
        "MINKQ_ERROR_UNSUPPORTED: e.g. CUDA asked for where there is none.",
    ),
    (sys::MINKQ_ERROR_OUT_OF_MEMORY, "OutOfMemoryError", Builtin::Memory, "MINKQ_ERROR_OUT_OF_MEMORY."),
    (sys::MINKQ_ERROR_DEVICE, "DeviceError", Builtin::Runtime, "MINKQ_ERROR_DEVICE: a CUDA runtime call failed."),
    (sys::MINKQ_ERROR_INTERNAL, "InternalError", Builtin::Runtime, "MINKQ_ERROR_INTERNAL."),
];

const MINKQ_ERROR_DOC: &str = "A minkq call failed.\n\n\
    ``status`` is the C status code, ``status_name`` its C name and ``message`` the library's\n\
    message, which names the offending element (``\"vertex 12 has a non-finite coordinate\"``).";

/// MinkqError, then the classes of CLASSES in its order.
static TYPES: GILOnceCell<Vec<Py<PyType>>> = GILOnceCell::new();

/// `MinkqError.__init__(self, message, status=None)`.
#[pyfunction]
#[pyo3(name = "__init__")]
fn minkq_error_init(slf: &PyAny, message: &PyAny, status: Option<&PyAny>) -> PyResult<()> {
    let py = slf.py();
    py.get_type::<PyException>().getattr("__init__")?.call1((slf, message))?;
    slf.setattr("message", message)?;
    if let Some(status) = status {
        if !status.is_none() {
            slf.setattr("status", status)?;
        }
    }
    Ok(())
}

/// `MinkqError.__str__(self)`: the library's message alone.
#[pyfunction]
#[pyo3(name = "__str__")]
fn minkq_error_str(slf: &PyAny) -> PyResult<PyObject> {
    Ok(slf.getattr("message")?.into())
}

/// `CapacityError.__init__(self, message, needed=0)`.
#[pyfunction]
#[pyo3(name = "__init__")]
fn capacity_error_init(slf: &PyAny, message: &PyAny, needed: Option<&PyAny>) -> PyResult<()> {
    minkq_error_init(slf, message, None)?;
    match needed {
        Some(needed) => slf.setattr("needed", needed),
        None => slf.setattr("needed", 0),
    }
}

/// A Rust function as a method of a class made with `type()`.
fn method<'py>(py: Python<'py>, function: &'py PyAny) -> PyResult<&'py PyAny> {
    py.import("functools")?.getattr("partialmethod")?.call1((function,))
}

/// `type(name, bases, namespace)`, the class's `__module__` the package that exports it.
fn make_type<'py>(py: Python<'py>, name: &str, bases: &'py PyTuple, namespace: &'py PyDict) -> PyResult<Py<PyType>> {
    namespace.set_item("__module__", "minkq")?;
    let made = py.get_type::<PyType>().call1((name, bases, namespace))?;
    Ok(made.downcast::<PyType>()?.into())
}

fn status_name(status: u32) -> &'static str {
    minkq::Error::from_status(status, "").status_name()
}

/// Creates the classes and adds them to the module `m`.
pub(crate) fn register(py: Python<'_>, m: &PyModule) -> PyResult<()> {
    let mut types = Vec::with_capacity(CLASSES.len() + 1);
    let namespace = PyDict::new(py);
    namespace.set_item("__doc__", MINKQ_ERROR_DOC)?;
    namespace.set_item("status", -1)?;
    namespace.set_item("status_name", "unknown minkq_status")?;
    namespace.set_item("__init__", method(py, wrap_pyfunction!(minkq_error_init, m)?)?)?;
    namespace.set_item("__str__", method(py, wrap_pyfunction!(minkq_error_str, m)?)?)?;
    let base = make_type(py, "MinkqError", PyTuple::new(py, [py.get_type::<PyException>()]), namespace)?;
    types.push(base.clone_ref(py));
    for (status, name, builtin, doc) in CLASSES {
        let bases = match builtin {
            Builtin::None => PyTuple::new(py, [base.as_ref(py)]),
            Builtin::Value => PyTuple::new(py, [base.as_ref(py), py.get_type::<PyValueError>()]),
            Builtin::Overflow => PyTuple::new(py, [base.as_ref(py), py.get_type::<PyOverflowError>()]),
            Builtin::Memory => PyTuple::new(py, [base.as_ref(py), py.get_type::<PyMemoryError>()]),
            Builtin::Runtime => PyTuple::new(py, [base.as_ref(py), py.get_type::<PyRuntimeError>()]),
        };
        let namespace = PyDict::new(py);
        namespace.set_item("__doc__", doc)?;
        namespace.set_item("status", status)?;
        namespace.set_item("status_name", status_name(status))?;
        if status == sys::MINKQ_ERROR_CAPACITY {
            namespace.set_item("__init__", method(py, wrap_pyfunction!(capacity_error_init, m)?)?)?;
        }
        types.push(make_type(py, name, bases, namespace)?);
    }
    for t in &types {
        m.add(t.as_ref(py).name()?, t.clone_ref(py))?;
    }
    let _ = TYPES.set(py, types);
    m.add_function(wrap_pyfunction!(exception, m)?)?;
    Ok(())
}

/// The exception for a C status: its class (MinkqError with the status for an unknown one),
/// the message, and for MINKQ_ERROR_CAPACITY the pairs needed.
#[pyfunction]
#[pyo3(name = "_exception")]
pub(crate) fn exception(py: Python<'_>, status: u32, message: &str, needed: Option<u64>) -> PyResult<PyObject> {
    let types = TYPES.get(py).expect("the classes are made when the module is loaded");
    let class = CLASSES.iter().position(|c| c.0 == status).map(|i| &types[i + 1]);
    let made = match class {
        Some(class) if status == sys::MINKQ_ERROR_CAPACITY => class.as_ref(py).call1((message, needed.unwrap_or(0)))?,
        Some(class) => class.as_ref(py).call1((message,))?,
        None => types[0].as_ref(py).call1((message, status))?,
    };
    Ok(made.into())
}

/// The exception for a minkq error.
pub(crate) fn to_py_err(py: Python<'_>, err: minkq::Error) -> PyErr {
    let needed = match &err {
        minkq::Error::Capacity { needed, .. } => Some(*needed),
        _ => None,
    };
    match exception(py, err.status(), err.message(), needed) {
        Ok(made) => PyErr::from_value(made.as_ref(py)),
        Err(failed) => failed,
    }
}
