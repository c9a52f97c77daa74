//! Safetensors checkpoints, loadable by PyTorch (`safetensors.torch.load_file`) and NumPy
//! (`safetensors.numpy.load_file`).
//!
//! Every tensor is F32, little-endian, with its PyTorch shape (a `Linear` weight is
//! (out, in)); the key is the network's tensor name, optionally behind a prefix so several
//! networks share a file (`actor.lstm.weight_ih`, `critic1.q.bias`, …). See [`crate::Actor`]
//! and [`crate::Critic`] for the names. Writes go to a temporary file that is renamed into
//! place, so a crash never leaves a half-written checkpoint.

use crate::error::NnError;
use crate::params::Params;
use safetensors::tensor::{Dtype, SafeTensors, TensorView};
use std::collections::HashMap;
use std::path::Path;

fn f32_bytes(v: &[f32]) -> Vec<u8> {
    v.iter().flat_map(|x| x.to_le_bytes()).collect()
}

/// A named tensor to write with [`save_tensors`].
#[derive(Clone, Debug, PartialEq)]
pub struct NamedTensor {
    /// Key in the file.
    pub name: String,
    /// Shape.
    pub shape: Vec<usize>,
    /// Row-major values (`shape.iter().product()` of them).
    pub data: Vec<f32>,
}

/// Writes named F32 tensors (plus string `metadata`) atomically to `path`.
pub fn save_tensors(
    path: &Path,
    tensors: &[NamedTensor],
    metadata: Option<HashMap<String, String>>,
) -> Result<(), NnError> {
    let bytes: Vec<(String, Vec<u8>, Vec<usize>)> = tensors
        .iter()
        .map(|t| (t.name.clone(), f32_bytes(&t.data), t.shape.clone()))
        .collect();
    let mut views = Vec::with_capacity(bytes.len());
    for (name, b, shape) in &bytes {
        let v = TensorView::new(Dtype::F32, shape.clone(), b).map_err(|e| NnError::Format {
            path: path.to_path_buf(),
            reason: format!("tensor `{name}`: {e}"),
        })?;
        views.push((name.clone(), v));
    }
    let out = safetensors::tensor::serialize(views, metadata).map_err(|e| NnError::Format {
        path: path.to_path_buf(),
        reason: e.to_string(),
    })?;
    let out = canonical_metadata(out);
    let io = |source| NnError::Io {
        path: path.to_path_buf(),
        source,
    };
    let tmp = path.with_extension("safetensors.tmp");
    std::fs::write(&tmp, &out).map_err(io)?;
    std::fs::rename(&tmp, path).map_err(io)
}

/// Rewrites the header of a serialised safetensors file with its `__metadata__` keys sorted.
///
/// The safetensors crate writes the metadata map in `HashMap` order, which changes from run to
/// run, so identical tensors would give files with different bytes (and hashes). The header is
/// JSON padded with spaces to a multiple of 8 bytes; the same entries in another order have the
/// same compact length, so the rewrite keeps every offset. Anything unexpected leaves the bytes
/// as they were.
fn canonical_metadata(mut bytes: Vec<u8>) -> Vec<u8> {
    let Some(len) = bytes
        .get(..8)
        .and_then(|b| <[u8; 8]>::try_from(b).ok())
        .map(|b| u64::from_le_bytes(b) as usize)
    else {
        return bytes;
    };
    let Some(header) = bytes.get(8..8 + len) else {
        return bytes;
    };
    let Ok(serde_json::Value::Object(mut top)) = serde_json::from_slice(header) else {
        return bytes;
    };
    let Some(serde_json::Value::Object(meta)) = top.get_mut("__metadata__") else {
        return bytes;
    };
    let sorted: std::collections::BTreeMap<String, serde_json::Value> =
        std::mem::take(meta).into_iter().collect();
    *meta = sorted.into_iter().collect();
    let Ok(text) = serde_json::to_vec(&top) else {
        return bytes;
    };
    if text.len() > len {
        return bytes;
    }
    let mut padded = text;
    padded.resize(len, b' ');
    bytes[8..8 + len].copy_from_slice(&padded);
    bytes
}

/// Reads every F32 tensor of a safetensors file, keyed by name. Other dtypes are an error
/// naming the tensor.
pub fn load_tensors(path: &Path) -> Result<HashMap<String, NamedTensor>, NnError> {
    let buf = std::fs::read(path).map_err(|source| NnError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let st = SafeTensors::deserialize(&buf).map_err(|e| NnError::Format {
        path: path.to_path_buf(),
        reason: e.to_string(),
    })?;
    let mut out = HashMap::new();
    for (name, view) in st.tensors() {
        if view.dtype() != Dtype::F32 {
            return Err(NnError::DtypeMismatch {
                path: path.to_path_buf(),
                name,
                found: format!("{:?}", view.dtype()),
            });
        }
        let data: Vec<f32> = view
            .data()
            .chunks_exact(4)
            .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
            .collect();
        out.insert(
            name.clone(),
            NamedTensor {
                name,
                shape: view.shape().to_vec(),
                data,
            },
        );
    }
    Ok(out)
}

/// Saves parameter sets, each under its key prefix (e.g. `("actor.", &actor_params)`; use
/// `""` for a single network).
pub fn save_params(path: &Path, sets: &[(&str, &Params)]) -> Result<(), NnError> {
    let mut tensors = Vec::new();
    for (prefix, p) in sets {
        for s in p.specs() {
            tensors.push(NamedTensor {
                name: format!("{prefix}{}", s.name),
                shape: s.shape.clone(),
                data: p.as_slice()[s.range()].to_vec(),
            });
        }
    }
    let mut meta = HashMap::new();
    meta.insert("format".to_string(), "pt".to_string());
    meta.insert(
        "producer".to_string(),
        format!("esrl-nn {}", env!("CARGO_PKG_VERSION")),
    );
    save_tensors(path, &tensors, Some(meta))
}

/// Loads parameter sets saved by [`save_params`]. Every tensor must be present with the
/// right shape and finite values; on any error nothing is modified. Extra tensors in the
/// file are ignored (one file may hold several networks).
pub fn load_params(path: &Path, sets: &mut [(&str, &mut Params)]) -> Result<(), NnError> {
    let file = load_tensors(path)?;
    let mut staged: Vec<Vec<f32>> = Vec::with_capacity(sets.len());
    for (prefix, p) in sets.iter() {
        let mut flat = vec![0.0f32; p.len()];
        for s in p.specs() {
            let name = format!("{prefix}{}", s.name);
            let Some(NamedTensor { shape, data, .. }) = file.get(&name) else {
                return Err(NnError::MissingTensor {
                    path: path.to_path_buf(),
                    name,
                });
            };
            if shape != &s.shape {
                return Err(NnError::ShapeMismatch {
                    path: path.to_path_buf(),
                    name,
                    expected: s.shape.clone(),
                    found: shape.clone(),
                });
            }
            if !data.iter().all(|v| v.is_finite()) {
                return Err(NnError::NonFinite {
                    path: path.to_path_buf(),
                    name,
                });
            }
            flat[s.range()].copy_from_slice(data);
        }
        staged.push(flat);
    }
    for ((_, p), flat) in sets.iter_mut().zip(staged) {
        p.set_flat(&flat)?;
    }
    Ok(())
}
