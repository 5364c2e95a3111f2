//! The quantities' columns in Python, from the library's column schema
//! (`eigenray::output::columns::Schema`; a scene with `"amplitudes"` has `amplitude`, `spreading`,
//! `coefficient`, `attenuation_db` and `amplitude_reason`): the columns of a `Rays` or an
//! `Arrivals` while they are filled, their rows, their numpy arrays, the attributes that read
//! them, a `Ray`'s values and an arrival dict's keys. Every part iterates over the schema's
//! columns, so that a new quantity of the library reaches Python without a line here. A
//! missing value is NaN, never 0.

use eigenray::amplitude::{Complex64, NoAmplitude};
use eigenray::output::columns::{Cell, Column, ColumnType, Entry, Schema};
use numpy::{
    Element, IntoPyArray, PyArray1, PyArrayMethods, PyReadwriteArray1, PyUntypedArrayMethods,
};
use pyo3::exceptions::{PyAttributeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use pyo3::{IntoPyObjectExt, PyTypeInfo};

/// A complex number that is not one (a missing amplitude or coefficient).
const NO_NUMBER: Complex64 = Complex64::new(f64::NAN, f64::NAN);

/// One column of a table while it is filled.
enum ColumnVec {
    /// Of a [`ColumnType::Float`] column.
    Float(Vec<f64>),
    /// Of a [`ColumnType::Complex`] column.
    Complex(Vec<Complex64>),
    /// Of a [`ColumnType::Why`] column.
    Why(Vec<Option<NoAmplitude>>),
}

/// The quantities' columns of a table (the schema's columns, in order), one entry per ray,
/// while they are filled.
pub(crate) struct QuantityColumns {
    /// The schema.
    schema: Schema,
    /// Its columns and their entries.
    columns: Vec<(&'static Column, ColumnVec)>,
}

impl QuantityColumns {
    /// The bytes of one ray's entries of `schema`'s columns.
    pub(crate) fn bytes_per_ray(schema: &Schema) -> u64 {
        schema
            .columns()
            .map(|c| match c.ty {
                ColumnType::Float => 8,
                ColumnType::Complex => 16,
                ColumnType::Why => std::mem::size_of::<Option<NoAmplitude>>() as u64,
            })
            .sum()
    }

    /// The columns of `schema` for `rays` rays, every entry missing until written.
    pub(crate) fn new(schema: Schema, rays: usize) -> QuantityColumns {
        let columns = schema
            .columns()
            .map(|c| {
                let column = match c.ty {
                    ColumnType::Float => ColumnVec::Float(vec![f64::NAN; rays]),
                    ColumnType::Complex => ColumnVec::Complex(vec![NO_NUMBER; rays]),
                    ColumnType::Why => ColumnVec::Why(vec![None; rays]),
                };
                (c, column)
            })
            .collect();
        QuantityColumns { schema, columns }
    }

    /// All its rows, for writing (`None` without columns).
    pub(crate) fn rows(&mut self) -> Option<QuantityRows<'_>> {
        if self.columns.is_empty() {
            return None;
        }
        let columns = self
            .columns
            .iter_mut()
            .map(|(_, c)| match c {
                ColumnVec::Float(v) => ColumnRows::Float(v),
                ColumnVec::Complex(v) => ColumnRows::Complex(v),
                ColumnVec::Why(v) => ColumnRows::Why(v),
            })
            .collect();
        Some(QuantityRows {
            schema: self.schema.clone(),
            columns,
        })
    }

    /// The columns as numpy arrays, and their reasons (worded when read).
    pub(crate) fn finish(self, py: Python<'_>) -> (QuantityArrays, Vec<WhyColumn>) {
        let mut arrays = Vec::with_capacity(self.columns.len());
        let mut whys = Vec::new();
        for (column, values) in self.columns {
            let array = match values {
                ColumnVec::Float(v) => Some(ColumnArray::Float(v.into_pyarray(py).unbind())),
                ColumnVec::Complex(v) => Some(ColumnArray::Complex(v.into_pyarray(py).unbind())),
                ColumnVec::Why(reasons) => {
                    whys.push(WhyColumn { column, reasons });
                    None
                }
            };
            arrays.push((column, array));
        }
        (QuantityArrays { columns: arrays }, whys)
    }
}

/// Why each ray's quantity has no value, one per ray (`None` where it has one or the ray
/// has no time): a [`ColumnType::Why`] column, kept beside the rays' reasons.
pub(crate) struct WhyColumn {
    /// The column.
    pub(crate) column: &'static Column,
    /// One per ray.
    pub(crate) reasons: Vec<Option<NoAmplitude>>,
}

/// The words of the column named `name` of `whys` (`None` without one).
pub(crate) fn why_words(whys: &[WhyColumn], name: &str) -> Option<Vec<Option<String>>> {
    let w = whys.iter().find(|w| w.column.name == name)?;
    Some(w.reasons.iter().map(|r| r.map(|r| r.to_string())).collect())
}

/// A numpy column of the quantities.
pub(crate) enum ColumnArray {
    /// `float64`.
    Float(Py<PyArray1<f64>>),
    /// `complex128`.
    Complex(Py<PyArray1<Complex64>>),
}

/// The quantities' columns of a `Rays` or an `Arrivals`, in the schema's order: numpy
/// arrays, shape `(n,)` each; a [`ColumnType::Why`] column's entries are kept with the
/// reasons (`None` here).
#[derive(Default)]
pub(crate) struct QuantityArrays {
    /// The columns.
    pub(crate) columns: Vec<(&'static Column, Option<ColumnArray>)>,
}

impl QuantityArrays {
    /// The numpy column named `name`.
    fn array(&self, name: &str) -> Option<&ColumnArray> {
        self.columns
            .iter()
            .find(|(c, _)| c.name == name)
            .and_then(|(_, a)| a.as_ref())
    }

    /// The float column `name`, when there is one.
    pub(crate) fn float_column<'py>(
        &self,
        py: Python<'py>,
        name: &str,
    ) -> Option<Bound<'py, PyArray1<f64>>> {
        match self.array(name)? {
            ColumnArray::Float(a) => Some(a.bind(py).clone()),
            ColumnArray::Complex(_) => None,
        }
    }

    /// Entry `i` of the float column `name`, when there is one.
    pub(crate) fn float_at(&self, py: Python<'_>, name: &str, i: usize) -> Option<f64> {
        match self.array(name)? {
            ColumnArray::Float(a) => a.bind(py).get_owned([i]),
            ColumnArray::Complex(_) => None,
        }
    }

    /// Its column names, in order.
    pub(crate) fn names(&self) -> Vec<&'static str> {
        self.columns.iter().map(|(c, _)| c.name).collect()
    }

    /// Its arrays under their names in `d` (a pickled state).
    pub(crate) fn set_items(&self, d: &Bound<'_, PyDict>) -> PyResult<()> {
        for (column, array) in &self.columns {
            match array {
                Some(ColumnArray::Float(a)) => d.set_item(column.name, a)?,
                Some(ColumnArray::Complex(a)) => d.set_item(column.name, a)?,
                None => {}
            }
        }
        Ok(())
    }

    /// The columns of a pickled state of `n` rays: each quantity whose first column is in
    /// `state`, its numpy columns read by `column` and its reasons by `why`.
    pub(crate) fn of_state(
        state: &Bound<'_, PyDict>,
        column_f64: impl Fn(&str) -> PyResult<Py<PyArray1<f64>>>,
        column_c128: impl Fn(&str) -> PyResult<Py<PyArray1<Complex64>>>,
        why: impl Fn(&str) -> PyResult<Vec<Option<NoAmplitude>>>,
    ) -> PyResult<(QuantityArrays, Vec<WhyColumn>)> {
        let mut arrays = QuantityArrays::default();
        let mut whys = Vec::new();
        for group in Schema::every().groups() {
            let Some(first) = group.first() else {
                continue;
            };
            if state.get_item(first.name)?.is_none_or(|v| v.is_none()) {
                continue;
            }
            for column in group {
                let array = match column.ty {
                    ColumnType::Float => Some(ColumnArray::Float(column_f64(column.name)?)),
                    ColumnType::Complex => Some(ColumnArray::Complex(column_c128(column.name)?)),
                    ColumnType::Why => {
                        whys.push(WhyColumn {
                            column,
                            reasons: why(column.name)?,
                        });
                        None
                    }
                };
                arrays.columns.push((column, array));
            }
        }
        Ok((arrays, whys))
    }

    /// Whether every numpy column holds `n` entries.
    pub(crate) fn all_of_length(&self, py: Python<'_>, n: usize) -> bool {
        self.columns.iter().all(|(_, a)| match a {
            Some(ColumnArray::Float(a)) => a.bind(py).len() == n,
            Some(ColumnArray::Complex(a)) => a.bind(py).len() == n,
            None => true,
        })
    }

    /// The attribute `name` of a `Rays` or an `Arrivals` (`owner`) that is a quantity's column:
    /// its array, the words of its reasons (`whys`, for a [`ColumnType::Why`] column), or
    /// `None` for a column of a quantity the scene does not ask for; `AttributeError` for any
    /// other name.
    pub(crate) fn attribute(
        &self,
        py: Python<'_>,
        owner: &str,
        name: &str,
        whys: impl FnOnce() -> Option<Vec<Option<String>>>,
    ) -> PyResult<Py<PyAny>> {
        match self.array(name) {
            Some(ColumnArray::Float(a)) => return Ok(a.clone_ref(py).into_any()),
            Some(ColumnArray::Complex(a)) => return Ok(a.clone_ref(py).into_any()),
            None => {}
        }
        if self.columns.iter().any(|(c, _)| c.name == name) {
            return whys().into_py_any(py);
        }
        if Schema::every().columns().any(|c| c.name == name) {
            return Ok(py.None());
        }
        Err(PyAttributeError::new_err(format!(
            "'{owner}' object has no attribute '{name}'"
        )))
    }

    /// The values of entry `i` under their names in `d` (an arrival's dict), the words of its
    /// reasons from `why(name, i)`.
    pub(crate) fn set_entry(
        &self,
        py: Python<'_>,
        d: &Bound<'_, PyDict>,
        i: usize,
        why: impl Fn(&str, usize) -> Option<String>,
    ) -> PyResult<()> {
        for (column, array) in &self.columns {
            match array {
                Some(ColumnArray::Float(a)) => d.set_item(column.name, at(py, a, i)?)?,
                Some(ColumnArray::Complex(a)) => d.set_item(column.name, at(py, a, i)?)?,
                None => d.set_item(column.name, why(column.name, i))?,
            }
        }
        Ok(())
    }

    /// Its numpy columns borrowed for writing in place (`busy` for a column in use).
    pub(crate) fn borrow<'py>(
        &self,
        py: Python<'py>,
        busy: impl Fn() -> PyErr,
    ) -> PyResult<Vec<OutColumn<'py>>> {
        let mut out = Vec::new();
        for (_, array) in &self.columns {
            match array {
                Some(ColumnArray::Float(a)) => out.push(OutColumn::Float(
                    a.bind(py).try_readwrite().map_err(|_| busy())?,
                )),
                Some(ColumnArray::Complex(a)) => out.push(OutColumn::Complex(
                    a.bind(py).try_readwrite().map_err(|_| busy())?,
                )),
                None => {}
            }
        }
        Ok(out)
    }
}

/// The entry of `array` at `i`; `ValueError` where there is none (an array reshaped since).
fn at<T: Element + Copy>(py: Python<'_>, array: &Py<PyArray1<T>>, i: usize) -> PyResult<T> {
    array
        .bind(py)
        .get_owned(i)
        .ok_or_else(|| PyValueError::new_err("the arrivals' arrays do not hold the arrival"))
}

/// A numpy column of an earlier `Rays`, borrowed for writing in place.
pub(crate) enum OutColumn<'py> {
    /// `float64`.
    Float(PyReadwriteArray1<'py, f64>),
    /// `complex128`.
    Complex(PyReadwriteArray1<'py, Complex64>),
}

/// The rows of `out`'s numpy columns and of the reasons `whys`, in the schema's order
/// (`contiguous` for a column that is not C-contiguous).
pub(crate) fn out_rows<'a>(
    schema: &Schema,
    out: &'a mut [OutColumn<'_>],
    whys: &'a mut [WhyColumn],
    contiguous: impl Fn() -> PyErr,
) -> PyResult<Option<QuantityRows<'a>>> {
    if out.is_empty() && whys.is_empty() {
        return Ok(None);
    }
    let (mut out, mut whys) = (out.iter_mut(), whys.iter_mut());
    let mut columns = Vec::new();
    for column in schema.columns() {
        let rows = match column.ty {
            ColumnType::Why => whys.next().map(|w| ColumnRows::Why(&mut w.reasons)),
            ColumnType::Float | ColumnType::Complex => match out.next() {
                Some(OutColumn::Float(a)) if a.is_c_contiguous() => Some(ColumnRows::Float(
                    a.as_slice_mut().map_err(|_| contiguous())?,
                )),
                Some(OutColumn::Complex(a)) if a.is_c_contiguous() => Some(ColumnRows::Complex(
                    a.as_slice_mut().map_err(|_| contiguous())?,
                )),
                _ => None,
            },
        };
        columns.push(rows.ok_or_else(&contiguous)?);
    }
    Ok(Some(QuantityRows {
        schema: schema.clone(),
        columns,
    }))
}

/// Rows of one column.
enum ColumnRows<'a> {
    /// Of a [`ColumnType::Float`] column.
    Float(&'a mut [f64]),
    /// Of a [`ColumnType::Complex`] column.
    Complex(&'a mut [Complex64]),
    /// Of a [`ColumnType::Why`] column.
    Why(&'a mut [Option<NoAmplitude>]),
}

/// Rows of the quantities' columns: one slice per column, all of the same rows.
pub(crate) struct QuantityRows<'a> {
    /// The schema whose columns they are.
    schema: Schema,
    /// The columns, in the schema's order.
    columns: Vec<ColumnRows<'a>>,
}

impl QuantityRows<'_> {
    /// The rows before `k` and from `k` on.
    pub(crate) fn split_at(self, k: usize) -> (Self, Self) {
        let (mut a, mut b) = (Vec::new(), Vec::new());
        for column in self.columns {
            let (x, y) = match column {
                ColumnRows::Float(v) => {
                    let (x, y) = v.split_at_mut(k);
                    (ColumnRows::Float(x), ColumnRows::Float(y))
                }
                ColumnRows::Complex(v) => {
                    let (x, y) = v.split_at_mut(k);
                    (ColumnRows::Complex(x), ColumnRows::Complex(y))
                }
                ColumnRows::Why(v) => {
                    let (x, y) = v.split_at_mut(k);
                    (ColumnRows::Why(x), ColumnRows::Why(y))
                }
            };
            a.push(x);
            b.push(y);
        }
        let schema = self.schema;
        (
            QuantityRows {
                schema: schema.clone(),
                columns: a,
            },
            QuantityRows { schema, columns: b },
        )
    }

    /// Row `i`: the quantities of `entry` (every number NaN where there is none).
    #[inline]
    pub(crate) fn write(&mut self, i: usize, entry: &Entry<'_>) {
        let mut columns = self.columns.iter_mut();
        self.schema
            .cells(entry, |cell| match (columns.next(), cell) {
                (Some(ColumnRows::Float(c)), Cell::Float(v)) => c[i] = v,
                (Some(ColumnRows::Complex(c)), Cell::Complex(v)) => c[i] = v,
                (Some(ColumnRows::Why(c)), Cell::Why(why)) => c[i] = why.reason(),
                _ => {}
            });
    }
}

/// The quantities of one `Ray` (or of one arrival) as Python values: each column's value,
/// in the schema's order (none for a scene that asks for no quantity).
#[derive(Default)]
pub(crate) struct RayValues {
    /// The columns and their values.
    values: Vec<(&'static Column, Cell)>,
}

impl RayValues {
    /// The values of `entry`, a ray of `scene`: NaN where it has no time or its quantity no
    /// value.
    pub(crate) fn new(scene: &eigenray::Scene, entry: &Entry<'_>) -> RayValues {
        let schema = Schema::of(scene);
        let mut columns = schema.columns();
        let mut values = Vec::new();
        schema.cells(entry, |cell| {
            if let Some(c) = columns.next() {
                values.push((c, cell));
            }
        });
        RayValues { values }
    }

    /// The attribute `name` of a `Ray` (`owner`): a quantity's value, or `None` for a
    /// column of a quantity its scene does not ask for; `AttributeError` for any other name.
    pub(crate) fn attribute(&self, py: Python<'_>, owner: &str, name: &str) -> PyResult<Py<PyAny>> {
        if let Some((_, cell)) = self.values.iter().find(|(c, _)| c.name == name) {
            return cell_object(py, *cell);
        }
        if Schema::every().columns().any(|c| c.name == name) {
            return Ok(py.None());
        }
        Err(PyAttributeError::new_err(format!(
            "'{owner}' object has no attribute '{name}'"
        )))
    }
}

/// A cell as a Python value: a float, a complex number, or the words of a reason (`None`).
fn cell_object(py: Python<'_>, cell: Cell) -> PyResult<Py<PyAny>> {
    match cell {
        Cell::Float(v) => v.into_py_any(py),
        Cell::Complex(c) => c.into_py_any(py),
        Cell::Why(why) => why.reason().map(|r| r.to_string()).into_py_any(py),
    }
}

/// The names of every quantity's columns, for `__dir__`.
pub(crate) fn every_name() -> Vec<&'static str> {
    Schema::every().columns().map(|c| c.name).collect()
}

/// The attribute names of `T` (its class's), with every quantity's columns.
pub(crate) fn dir_of<T: PyTypeInfo>(py: Python<'_>) -> PyResult<Vec<String>> {
    let mut names: Vec<String> = T::type_object(py).dir()?.extract()?;
    names.extend(every_name().into_iter().map(String::from));
    names.sort();
    names.dedup();
    Ok(names)
}
