//! The one value type: a dense row-major f32 matrix.

/// A dense row-major `(rows, cols)` matrix of f32.
///
/// Sequence batches use the **time-major** convention: a batch of `B` sequences of `T` steps
/// with `D` features is a `(T·B, D)` matrix whose row `t·B + b` is step `t` of sequence `b`.
/// That makes each time step a contiguous `(B, D)` block, which is what the LSTM needs.
#[derive(Debug, PartialEq, Default)]
pub struct Tensor {
    rows: usize,
    cols: usize,
    data: Vec<f32>,
}

impl Clone for Tensor {
    fn clone(&self) -> Self {
        Self {
            rows: self.rows,
            cols: self.cols,
            data: crate::pool::copy(&self.data),
        }
    }
}

impl Drop for Tensor {
    fn drop(&mut self) {
        crate::pool::recycle(std::mem::take(&mut self.data));
    }
}

impl Tensor {
    /// A `(rows, cols)` matrix of zeros.
    pub fn zeros(rows: usize, cols: usize) -> Self {
        Self {
            rows,
            cols,
            data: crate::pool::zeros(rows * cols),
        }
    }

    /// A `(rows, cols)` matrix whose contents are unspecified (every element must be
    /// written before it is read).
    pub(crate) fn uninit(rows: usize, cols: usize) -> Self {
        Self {
            rows,
            cols,
            data: crate::pool::dirty(rows * cols),
        }
    }

    /// A `(rows, cols)` matrix filled with `value`.
    pub fn full(rows: usize, cols: usize, value: f32) -> Self {
        Self {
            rows,
            cols,
            data: vec![value; rows * cols],
        }
    }

    /// Wraps a row-major buffer.
    ///
    /// # Panics
    /// If `data.len() != rows * cols` (a programming error, not input).
    pub fn from_vec(rows: usize, cols: usize, data: Vec<f32>) -> Self {
        assert_eq!(
            data.len(),
            rows * cols,
            "Tensor::from_vec: {rows}x{cols} needs {} values, got {}",
            rows * cols,
            data.len()
        );
        Self { rows, cols, data }
    }

    /// Copies a row-major slice.
    pub fn from_slice(rows: usize, cols: usize, data: &[f32]) -> Self {
        Self::from_vec(rows, cols, crate::pool::copy(data))
    }

    /// A `(1, 1)` matrix.
    pub fn scalar(value: f32) -> Self {
        Self {
            rows: 1,
            cols: 1,
            data: vec![value],
        }
    }

    /// Number of rows.
    pub fn rows(&self) -> usize {
        self.rows
    }

    /// Number of columns.
    pub fn cols(&self) -> usize {
        self.cols
    }

    /// `(rows, cols)`.
    pub fn shape(&self) -> (usize, usize) {
        (self.rows, self.cols)
    }

    /// Number of elements.
    pub fn len(&self) -> usize {
        self.data.len()
    }

    /// True when the matrix holds no element.
    pub fn is_empty(&self) -> bool {
        self.data.is_empty()
    }

    /// The row-major values.
    pub fn data(&self) -> &[f32] {
        &self.data
    }

    /// The row-major values, mutable.
    pub fn data_mut(&mut self) -> &mut [f32] {
        &mut self.data
    }

    /// Consumes the tensor, returning its buffer.
    pub fn into_vec(mut self) -> Vec<f32> {
        std::mem::take(&mut self.data)
    }

    /// Row `r` as a slice.
    pub fn row(&self, r: usize) -> &[f32] {
        &self.data[r * self.cols..(r + 1) * self.cols]
    }

    /// Element `(r, c)`.
    pub fn get(&self, r: usize, c: usize) -> f32 {
        self.data[r * self.cols + c]
    }

    /// Rows `start..start + n` as a new tensor.
    pub fn rows_range(&self, start: usize, n: usize) -> Tensor {
        let c = self.cols;
        Tensor {
            rows: n,
            cols: c,
            data: crate::pool::copy(&self.data[start * c..(start + n) * c]),
        }
    }

    /// The single value of a `(1, 1)` tensor.
    ///
    /// # Panics
    /// If the tensor is not `(1, 1)`.
    pub fn item(&self) -> f32 {
        assert_eq!(
            self.shape(),
            (1, 1),
            "Tensor::item on a {}x{} tensor",
            self.rows,
            self.cols
        );
        self.data[0]
    }

    /// Mean of all elements (0 for an empty tensor).
    pub fn mean(&self) -> f32 {
        if self.data.is_empty() {
            return 0.0;
        }
        (self.data.iter().map(|&v| v as f64).sum::<f64>() / self.data.len() as f64) as f32
    }

    /// True when every element is finite.
    pub fn all_finite(&self) -> bool {
        self.data.iter().all(|v| v.is_finite())
    }

    /// Reorders a batch-major `(B·T, D)` matrix (row `b·T + t`) into the time-major layout
    /// `(T·B, D)` (row `t·B + b`) the sequence ops use.
    pub fn batch_major_to_time_major(&self, batch: usize) -> Tensor {
        transpose_blocks(self, batch)
    }

    /// Inverse of [`Tensor::batch_major_to_time_major`].
    pub fn time_major_to_batch_major(&self, batch: usize) -> Tensor {
        assert!(
            batch > 0 && self.rows.is_multiple_of(batch),
            "time_major_to_batch_major: {} rows not a multiple of batch {batch}",
            self.rows
        );
        transpose_blocks(self, self.rows / batch)
    }
}

/// Views `rows` as an `(outer, inner)` grid of rows and transposes the grid.
fn transpose_blocks(x: &Tensor, outer: usize) -> Tensor {
    assert!(
        outer > 0 && x.rows.is_multiple_of(outer),
        "sequence reorder: {} rows not a multiple of {outer}",
        x.rows
    );
    let inner = x.rows / outer;
    let c = x.cols;
    let mut out = Tensor::uninit(x.rows, c);
    for o in 0..outer {
        for i in 0..inner {
            let src = (o * inner + i) * c;
            let dst = (i * outer + o) * c;
            out.data[dst..dst + c].copy_from_slice(&x.data[src..src + c]);
        }
    }
    out
}
