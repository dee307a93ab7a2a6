use std::ffi::CStr;
use std::fmt;

use crate::sys;

/// A failed minkq call: the C API's status code as a variant, carrying the library's message
/// (which names the offending element, e.g. `"vertex 12 has a non-finite coordinate (nan, 0, 1)"`).
///
/// ```
/// use minkq::{Device, Error};
/// let err = Device::new("tpu").unwrap_err();
/// assert!(matches!(err, Error::InvalidArgument(_)));
/// assert_eq!(err.status_name(), "MINKQ_ERROR_INVALID_ARGUMENT");
/// assert!(err.message().contains("unknown device spec"));
/// ```
#[derive(Debug, Clone, PartialEq, Eq)]
#[non_exhaustive]
pub enum Error {
    /// `MINKQ_ERROR_INVALID_ARGUMENT`: a bad enum, stride, flag combination, count or spec.
    InvalidArgument(String),
    /// `MINKQ_ERROR_NON_FINITE`: NaN or infinity in a coordinate or the radius.
    NonFinite(String),
    /// `MINKQ_ERROR_INDEX_OUT_OF_RANGE`: a negative or too large vertex index.
    IndexOutOfRange(String),
    /// `MINKQ_ERROR_SIZE_OVERFLOW`: a count whose byte size overflows, or over its limit: 2^31 - 2
    /// query elements, 2^30 + 1 elements of a tree (vertices, triangles, edges, boxes).
    SizeOverflow(String),
    /// `MINKQ_ERROR_CAPACITY`: the output buffer holds fewer pairs than the query found;
    /// `needed` is the exact count.
    Capacity {
        /// The exact number of pairs the query found.
        needed: u64,
        /// The library's message.
        message: String,
    },
    /// `MINKQ_ERROR_UNSUPPORTED`: e.g. CUDA asked for where there is none.
    Unsupported(String),
    /// `MINKQ_ERROR_OUT_OF_MEMORY`.
    OutOfMemory(String),
    /// `MINKQ_ERROR_DEVICE`: a CUDA runtime call failed.
    Device(String),
    /// `MINKQ_ERROR_INTERNAL`.
    Internal(String),
    /// A status this crate does not know (a newer library).
    Unknown {
        /// The raw `minkq_status` value.
        status: u32,
        /// The library's message.
        message: String,
    },
}

/// `Result` with [`Error`] as the error type.
///
/// ```
/// fn open() -> minkq::Result<minkq::Device> {
///     minkq::Device::new("cpu")
/// }
/// assert!(open().is_ok());
/// ```
pub type Result<T, E = Error> = std::result::Result<T, E>;

impl Error {
    /// The error for a failure status (`minkq_status` value) and message, as the C API reports
    /// it. A Capacity error made here has `needed` 0.
    ///
    /// ```
    /// use minkq::Error;
    /// let e = Error::from_status(2, "vertex 0 has a non-finite coordinate");
    /// assert_eq!(e, Error::NonFinite("vertex 0 has a non-finite coordinate".into()));
    /// assert_eq!(Error::from_status(42, "?").status(), 42);
    /// ```
    pub fn from_status(status: u32, message: impl Into<String>) -> Error {
        let message = message.into();
        match status {
            sys::MINKQ_ERROR_INVALID_ARGUMENT => Error::InvalidArgument(message),
            sys::MINKQ_ERROR_NON_FINITE => Error::NonFinite(message),
            sys::MINKQ_ERROR_INDEX_OUT_OF_RANGE => Error::IndexOutOfRange(message),
            sys::MINKQ_ERROR_SIZE_OVERFLOW => Error::SizeOverflow(message),
            sys::MINKQ_ERROR_CAPACITY => Error::Capacity { needed: 0, message },
            sys::MINKQ_ERROR_UNSUPPORTED => Error::Unsupported(message),
            sys::MINKQ_ERROR_OUT_OF_MEMORY => Error::OutOfMemory(message),
            sys::MINKQ_ERROR_DEVICE => Error::Device(message),
            sys::MINKQ_ERROR_INTERNAL => Error::Internal(message),
            status => Error::Unknown { status, message },
        }
    }

    /// The error for `status` with the message of the last failed call on this thread.
    pub(crate) fn last(status: sys::minkq_status) -> Error {
        // SAFETY: the library returns a valid NUL-terminated string, valid until the next
        // minkq call on this thread; it is copied at once.
        let message = unsafe { CStr::from_ptr(sys::minkq_last_error_message()) };
        Error::from_status(status, message.to_string_lossy().into_owned())
    }

    /// The C status code (`minkq_status` value).
    ///
    /// ```
    /// let err = minkq::Device::new("tpu").unwrap_err();
    /// assert_eq!(err.status(), minkq::sys::MINKQ_ERROR_INVALID_ARGUMENT);
    /// ```
    pub fn status(&self) -> u32 {
        match self {
            Error::InvalidArgument(_) => sys::MINKQ_ERROR_INVALID_ARGUMENT,
            Error::NonFinite(_) => sys::MINKQ_ERROR_NON_FINITE,
            Error::IndexOutOfRange(_) => sys::MINKQ_ERROR_INDEX_OUT_OF_RANGE,
            Error::SizeOverflow(_) => sys::MINKQ_ERROR_SIZE_OVERFLOW,
            Error::Capacity { .. } => sys::MINKQ_ERROR_CAPACITY,
            Error::Unsupported(_) => sys::MINKQ_ERROR_UNSUPPORTED,
            Error::OutOfMemory(_) => sys::MINKQ_ERROR_OUT_OF_MEMORY,
            Error::Device(_) => sys::MINKQ_ERROR_DEVICE,
            Error::Internal(_) => sys::MINKQ_ERROR_INTERNAL,
            Error::Unknown { status, .. } => *status,
        }
    }

    /// The C name of the status, e.g. `"MINKQ_ERROR_CAPACITY"`.
    ///
    /// ```
    /// let err = minkq::Error::from_status(5, "too many pairs");
    /// assert_eq!(err.status_name(), "MINKQ_ERROR_CAPACITY");
    /// ```
    pub fn status_name(&self) -> &'static str {
        // SAFETY: minkq_status_name returns a static string for any value.
        let name = unsafe { CStr::from_ptr(sys::minkq_status_name(self.status())) };
        name.to_str().unwrap_or("unknown minkq_status")
    }

    /// The library's message.
    ///
    /// ```
    /// let err = minkq::Device::new("gpu").unwrap_err();
    /// assert_eq!(err.message(), r#"unknown device spec "gpu" (use "cpu", "cuda", "cuda:N" or "auto")"#);
    /// ```
    pub fn message(&self) -> &str {
        match self {
            Error::InvalidArgument(m)
            | Error::NonFinite(m)
            | Error::IndexOutOfRange(m)
            | Error::SizeOverflow(m)
            | Error::Unsupported(m)
            | Error::OutOfMemory(m)
            | Error::Device(m)
            | Error::Internal(m) => m,
            Error::Capacity { message, .. } | Error::Unknown { message, .. } => message,
        }
    }
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}: {}", self.status_name(), self.message())
    }
}

impl std::error::Error for Error {}

/// Ok for `MINKQ_SUCCESS`, else the error with the library's message.
pub(crate) fn check(status: sys::minkq_status) -> Result<()> {
    if status == sys::MINKQ_SUCCESS {
        Ok(())
    } else {
        Err(Error::last(status))
    }
}
