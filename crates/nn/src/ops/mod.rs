//! The ops: each file holds forwards (as `Graph` methods) and, beside each, its backward.

pub(crate) mod elementwise;
pub(crate) mod linear;
pub(crate) mod lstm;
pub(crate) mod policy;
pub(crate) mod reduce;
pub(crate) mod shape;

/// Activation fused into a [`crate::Linear`] op.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Act {
    /// Identity.
    #[default]
    None,
    /// max(x, 0).
    Relu,
    /// tanh(x).
    Tanh,
}
