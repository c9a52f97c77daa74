//! A network's parameters: one flat f32 buffer plus named tensor slots.
//!
//! Keeping every weight of a network in one contiguous vector makes the ES's flat view, Polyak
//! averaging, Adam and checkpointing single loops over one slice.

use crate::error::NnError;
use std::sync::atomic::{AtomicU64, Ordering};

static NEXT_ID: AtomicU64 = AtomicU64::new(1);

fn fresh_id() -> u64 {
    NEXT_ID.fetch_add(1, Ordering::Relaxed)
}

/// One named tensor inside a [`Params`] buffer.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ParamSpec {
    /// Stable name, e.g. `lstm.weight_ih` (the safetensors key).
    pub name: String,
    /// PyTorch shape, e.g. `[400, 256]` for a weight of 400 outputs and 256 inputs.
    pub shape: Vec<usize>,
    /// Offset of the first element in the flat buffer.
    pub offset: usize,
    /// Whether L2 regularisation applies (weights yes, biases no, as MATLAB's default
    /// `BiasL2Factor = 0`).
    pub decay: bool,
}

impl ParamSpec {
    /// Number of elements.
    pub fn len(&self) -> usize {
        self.shape.iter().product()
    }

    /// True for a tensor with no element.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The flat index range of this tensor.
    pub fn range(&self) -> std::ops::Range<usize> {
        self.offset..self.offset + self.len()
    }
}

/// All parameters of one network in one flat row-major buffer, with named slots.
///
/// Every `Params` has an identity (cloning makes a new one) so that a [`crate::Graph`] can
/// tell the parameter sets it uses apart and [`crate::Gradients::of`] can return each one's
/// gradient.
#[derive(Debug)]
pub struct Params {
    id: u64,
    values: Vec<f32>,
    specs: Vec<ParamSpec>,
}

impl Clone for Params {
    fn clone(&self) -> Self {
        Self {
            id: fresh_id(),
            values: self.values.clone(),
            specs: self.specs.clone(),
        }
    }
}

impl Default for Params {
    fn default() -> Self {
        Self::new()
    }
}

impl Params {
    /// An empty set.
    pub fn new() -> Self {
        Self {
            id: fresh_id(),
            values: Vec::new(),
            specs: Vec::new(),
        }
    }

    /// Appends a tensor initialised by `init` and returns its offset.
    ///
    /// # Panics
    /// If `name` is already used (a programming error).
    pub fn add(
        &mut self,
        name: &str,
        shape: &[usize],
        decay: bool,
        mut init: impl FnMut() -> f32,
    ) -> usize {
        assert!(
            !self.specs.iter().any(|s| s.name == name),
            "duplicate parameter name `{name}`"
        );
        let offset = self.values.len();
        let n: usize = shape.iter().product();
        self.values.extend((0..n).map(|_| init()));
        self.specs.push(ParamSpec {
            name: name.to_string(),
            shape: shape.to_vec(),
            offset,
            decay,
        });
        offset
    }

    /// Identity of this set (unique per process; clones get a new one).
    pub fn id(&self) -> u64 {
        self.id
    }

    /// Total number of scalars.
    pub fn len(&self) -> usize {
        self.values.len()
    }

    /// True when there is no parameter.
    pub fn is_empty(&self) -> bool {
        self.values.is_empty()
    }

    /// The named tensors in buffer order.
    pub fn specs(&self) -> &[ParamSpec] {
        &self.specs
    }

    /// The flat vector (a view; the ES's genome).
    pub fn as_slice(&self) -> &[f32] {
        &self.values
    }

    /// The flat vector, mutable.
    pub fn as_mut_slice(&mut self) -> &mut [f32] {
        &mut self.values
    }

    /// A copy of the flat vector.
    pub fn to_flat(&self) -> Vec<f32> {
        self.values.clone()
    }

    /// Overwrites all parameters from a flat vector.
    pub fn set_flat(&mut self, flat: &[f32]) -> Result<(), NnError> {
        if flat.len() != self.values.len() {
            return Err(NnError::LengthMismatch {
                what: "flat parameter vector".into(),
                expected: self.values.len(),
                found: flat.len(),
            });
        }
        self.values.copy_from_slice(flat);
        Ok(())
    }

    /// The values of tensor `name`.
    pub fn tensor(&self, name: &str) -> Option<&[f32]> {
        self.specs
            .iter()
            .find(|s| s.name == name)
            .map(|s| &self.values[s.range()])
    }

    /// The values of tensor `name`, mutable.
    pub fn tensor_mut(&mut self, name: &str) -> Option<&mut [f32]> {
        let r = self.specs.iter().find(|s| s.name == name)?.range();
        Some(&mut self.values[r])
    }

    /// Polyak averaging (paper eq. 7): `self ← τ·source + (1 − τ)·self`.
    pub fn polyak_update(&mut self, source: &Params, tau: f32) -> Result<(), NnError> {
        if source.len() != self.len() {
            return Err(NnError::LengthMismatch {
                what: "Polyak source parameters".into(),
                expected: self.len(),
                found: source.len(),
            });
        }
        lerp(&mut self.values, &source.values, tau);
        Ok(())
    }

    /// Copies all values from `source` (a hard target update, eq. 2).
    pub fn copy_from(&mut self, source: &Params) -> Result<(), NnError> {
        self.set_flat(&source.values)
    }
}

crate::kern::simd_fn! {
    /// t ← t + τ(s − t).
    fn lerp<'a>(t: &'a mut [f32], s: &'a [f32], tau: f32) {
        for (t, &s) in t.iter_mut().zip(s) {
            *t += tau * (s - *t);
        }
    }
}
