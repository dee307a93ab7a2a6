//! Array arguments: buffer-protocol arrays (numpy) and the package's raw descriptors, viewed as
//! rows of a record type, and a scene's vertex rows of either precision.
use std::mem;
use std::slice;

use minkq::{Buffer, CountOut, Memory, PairsOut};
use pyo3::buffer::{Element, PyBuffer};
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyTuple;

/// A buffer viewed as rows of `R` (each `per_row` items of `T`, with trailing dimensions
/// `trailing`): a C-contiguous array of shape (n, *trailing).
pub(crate) struct Rows<T: Element> {
    pub(crate) buffer: PyBuffer<T>,
    pub(crate) rows: usize,
}

impl<T: Element> Rows<T> {
    pub(crate) fn get(obj: &PyAny, name: &str, trailing: &[usize], writable: bool) -> PyResult<Rows<T>> {
        let buffer = PyBuffer::<T>::get(obj).map_err(|e| {
            PyTypeError::new_err(format!("{name}: expected a {} array: {e}", std::any::type_name::<T>()))
        })?;
        let shape = buffer.shape();
        if shape.len() != trailing.len() + 1 || shape[1..] != *trailing {
            let wanted: Vec<String> = trailing.iter().map(|d| d.to_string()).collect();
            return Err(PyValueError::new_err(format!(
                "{name}: expected shape (n, {}), got {shape:?}",
                wanted.join(", ")
            )));
        }
        if !buffer.is_c_contiguous() {
            return Err(PyValueError::new_err(format!("{name}: expected a C-contiguous array")));
        }
        if writable && buffer.readonly() {
            return Err(PyValueError::new_err(format!("{name}: the array is read-only")));
        }
        // pyo3 0.17's element check takes a byte-swapped buffer ('>' on a little-endian host) for
        // a native one: refuse one here rather than read its values swapped.
        let order = buffer.format().to_bytes().first().copied();
        let swapped =
            if cfg!(target_endian = "little") { matches!(order, Some(b'>') | Some(b'!')) } else { order == Some(b'<') };
        if swapped {
            return Err(PyTypeError::new_err(format!(
                "{name}: expected native byte order, got buffer format {:?}",
                buffer.format()
            )));
        }
        let rows = shape[0];
        Ok(Rows { buffer, rows })
    }

    /// The rows as a mutable slice of `R`, which must be `trailing`'s product of `T`s.
    ///
    /// # Safety
    /// `R` is a plain array of that many `T`s, the buffer is writable (checked in `get`) and not otherwise
    /// borrowed while the slice lives.
    pub(crate) unsafe fn as_mut_slice<R>(&mut self) -> &mut [R] {
        if self.rows == 0 {
            &mut []
        } else {
            slice::from_raw_parts_mut(self.buffer.buf_ptr() as *mut R, self.rows)
        }
    }
}

/// An array argument: a buffer-protocol array (numpy), or a raw descriptor `(address,
/// byte_stride, count, device)` built by the package (minkq._interop) for DLPack and CUDA
/// array interface objects, which it keeps alive during the call.
pub(crate) enum Array<T: Element> {
    Host { rows: Rows<T>, row_bytes: usize },
    Raw { address: usize, byte_stride: usize, count: usize, memory: Memory },
}

impl<T: Element> Array<T> {
    pub(crate) fn get(obj: &PyAny, name: &str, trailing: &[usize], writable: bool) -> PyResult<Array<T>> {
        if let Ok(tuple) = obj.downcast::<PyTuple>() {
            let (address, byte_stride, count, device): (usize, usize, usize, bool) = tuple.extract().map_err(|e| {
                PyTypeError::new_err(format!(
                    "{name}: expected a raw descriptor (address, byte_stride, count, device): {e}"
                ))
            })?;
            let memory = if device { Memory::Device } else { Memory::Host };
            return Ok(Array::Raw { address, byte_stride, count, memory });
        }
        let rows = Rows::get(obj, name, trailing, writable)?;
        let row_bytes = trailing.iter().product::<usize>() * mem::size_of::<T>();
        Ok(Array::Host { rows, row_bytes })
    }

    /// The records as a minkq buffer.
    ///
    /// # Safety
    /// A raw descriptor describes memory that stays readable while the buffer is used (the
    /// package's promise).
    pub(crate) unsafe fn buffer(&self) -> Buffer<'_> {
        match self {
            Array::Host { rows, row_bytes } => {
                Buffer::from_raw_parts(rows.buffer.buf_ptr() as *const _, *row_bytes, rows.rows, Memory::Host)
            }
            Array::Raw { address, byte_stride, count, memory } => {
                Buffer::from_raw_parts(*address as *const _, *byte_stride, *count, *memory)
            }
        }
    }

    /// The rows as a pair output (rows of 2 int32, packed).
    ///
    /// # Safety
    /// As `buffer`, writable, packed, and not otherwise used during the call.
    pub(crate) unsafe fn pairs_out(&mut self) -> PairsOut<'_> {
        match self {
            Array::Host { rows, .. } => {
                PairsOut::from_raw_parts(rows.buffer.buf_ptr() as *mut i32, rows.rows, Memory::Host)
            }
            Array::Raw { address, count, memory, .. } => {
                PairsOut::from_raw_parts(*address as *mut i32, *count, *memory)
            }
        }
    }
}

impl Array<u64> {
    /// The one-element array as a count output.
    ///
    /// # Safety
    /// As `pairs_out`, for one u64.
    pub(crate) unsafe fn count_out(&mut self) -> CountOut<'_> {
        match self {
            Array::Host { rows, .. } => CountOut::from_raw_parts(rows.buffer.buf_ptr() as *mut u64, Memory::Host),
            Array::Raw { address, memory, .. } => CountOut::from_raw_parts(*address as *mut u64, *memory),
        }
    }

    /// A writable one-element uint64 array (numpy, or a raw descriptor of one).
    pub(crate) fn count(obj: &PyAny, name: &str) -> PyResult<Array<u64>> {
        let array = Array::<u64>::get(obj, name, &[], true)?;
        let rows = match &array {
            Array::Host { rows, .. } => rows.rows,
            Array::Raw { count, .. } => *count,
        };
        if rows != 1 {
            return Err(PyValueError::new_err(format!("{name}: expected shape (1,), got {rows} elements")));
        }
        Ok(array)
    }
}

/// A scene's vertex rows: 3 floats each, or 3 doubles each in a float64 scene
/// (MINKQ_SCENE_FLOAT64, whose every vertex buffer the library reads as doubles).
pub(crate) enum Vertices {
    Float32(Array<f32>),
    Float64(Array<f64>),
}

impl Vertices {
    pub(crate) fn get(obj: &PyAny, name: &str, float64: bool) -> PyResult<Vertices> {
        Ok(if float64 {
            Vertices::Float64(Array::get(obj, name, &[3], false)?)
        } else {
            Vertices::Float32(Array::get(obj, name, &[3], false)?)
        })
    }

    /// The rows as a minkq buffer (record stride 12 or 24 bytes for numpy rows).
    ///
    /// # Safety
    /// As `Array::buffer`.
    pub(crate) unsafe fn buffer(&self) -> Buffer<'_> {
        match self {
            Vertices::Float32(array) => array.buffer(),
            Vertices::Float64(array) => array.buffer(),
        }
    }
}
