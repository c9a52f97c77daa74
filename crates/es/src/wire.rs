//! The wire format of remote evaluation: a [`Genome`] goes out to a worker and its
//! [`Evaluation`] comes back as compact little-endian bytes, so that a generation can move
//! between a driver and workers in other processes or on other machines (the next step is a
//! Ray evaluator) at a known, small cost. Decoding gives back exactly what was encoded, bit
//! for bit, so an evaluator that ships genomes this way computes what the local one does.
//!
//! A genome: `b"ESG1"`, index `u32`, action seed `u64`, K `u32` and K initial-state seeds
//! `u64`, R `u32` and R rollouts (mode `u8`: 0 deterministic, 1 explore; scored `u8`), P `u32`
//! and P parameters `f32`.
//!
//! An evaluation: `b"ESE1"`, fitness `f64`, E `u32`, then per episode: steps T `u32`,
//! observation width O `u32`, action width A `u32`, return `f64`, truncated `u8`, T terminal
//! flags `u8`, a layout byte, the observations, the actions (T·A `f32`) and the rewards
//! (T `f32`). Within an episode each step's next observation is the following step's
//! observation, so layout 1 sends T + 1 observation rows (the last is the final next
//! observation), half of what sending both would take; layout 0 sends T rows of each, for
//! episodes where the two differ.

use crate::evaluate::{Evaluation, Genome, RolloutSpec};
use esrl_agents::{ActMode, Episode};
use thiserror::Error;

const GENOME_MAGIC: &[u8; 4] = b"ESG1";
const EVALUATION_MAGIC: &[u8; 4] = b"ESE1";

/// Bytes that do not decode.
#[derive(Debug, Error, PartialEq, Eq)]
pub enum WireError {
    /// The bytes end before `what`.
    #[error("the bytes end inside {what}")]
    Truncated {
        /// The field being read.
        what: &'static str,
    },
    /// The bytes do not start with the format's tag.
    #[error("not {expected} bytes (they start with {found:?})")]
    Magic {
        /// The format expected.
        expected: &'static str,
        /// The first bytes found.
        found: Vec<u8>,
    },
    /// A field holds a value the format does not have.
    #[error("{what} = {value}: not a valid value")]
    Value {
        /// The field.
        what: &'static str,
        /// Its value.
        value: u64,
    },
    /// Bytes are left after the last field.
    #[error("{0} bytes left after the end")]
    Trailing(usize),
}

/// A genome as bytes.
pub fn encode_genome(genome: &Genome) -> Vec<u8> {
    let mut out = Vec::with_capacity(32 + 8 * genome.env_seeds.len() + 4 * genome.params.len());
    out.extend_from_slice(GENOME_MAGIC);
    put_u32(&mut out, genome.index);
    out.extend_from_slice(&genome.action_seed.to_le_bytes());
    put_u32(&mut out, genome.env_seeds.len());
    for s in &genome.env_seeds {
        out.extend_from_slice(&s.to_le_bytes());
    }
    put_u32(&mut out, genome.rollouts.len());
    for r in &genome.rollouts {
        out.push(match r.mode {
            ActMode::Deterministic => 0,
            ActMode::Explore => 1,
        });
        out.push(u8::from(r.scored));
    }
    put_u32(&mut out, genome.params.len());
    put_f32s(&mut out, &genome.params);
    out
}

/// The genome in `bytes`.
pub fn decode_genome(bytes: &[u8]) -> Result<Genome, WireError> {
    let mut r = Reader::new(bytes);
    r.magic(GENOME_MAGIC, "genome")?;
    let index = r.u32("index")? as usize;
    let action_seed = r.u64("action seed")?;
    let k = r.u32("initial-state count")? as usize;
    let env_seeds = (0..k)
        .map(|_| r.u64("initial-state seed"))
        .collect::<Result<_, _>>()?;
    let n = r.u32("rollout count")? as usize;
    let mut rollouts = Vec::with_capacity(n.min(64));
    for _ in 0..n {
        let mode = match r.u8("rollout mode")? {
            0 => ActMode::Deterministic,
            1 => ActMode::Explore,
            v => {
                return Err(WireError::Value {
                    what: "rollout mode",
                    value: u64::from(v),
                })
            }
        };
        let scored = r.flag("rollout scored")?;
        rollouts.push(RolloutSpec { mode, scored });
    }
    let p = r.u32("parameter count")? as usize;
    let params = r.f32s(p, "parameters")?;
    r.end()?;
    Ok(Genome {
        index,
        params,
        action_seed,
        env_seeds,
        rollouts,
    })
}

/// An evaluation as bytes.
pub fn encode_evaluation(evaluation: &Evaluation) -> Vec<u8> {
    let floats: usize = evaluation
        .episodes
        .iter()
        .map(|e| e.obs.len() + e.obs_dim + e.action.len() + e.reward.len())
        .sum();
    let mut out = Vec::with_capacity(16 + 4 * floats + 32 * evaluation.episodes.len());
    out.extend_from_slice(EVALUATION_MAGIC);
    out.extend_from_slice(&evaluation.fitness.to_le_bytes());
    put_u32(&mut out, evaluation.episodes.len());
    for ep in &evaluation.episodes {
        let (t, o) = (ep.len(), ep.obs_dim);
        put_u32(&mut out, t);
        put_u32(&mut out, o);
        put_u32(&mut out, ep.act_dim);
        out.extend_from_slice(&ep.ret.to_le_bytes());
        out.push(u8::from(ep.truncated));
        out.extend(ep.terminated.iter().map(|&d| u8::from(d)));
        // Bit-for-bit comparison: next_obs[t] is obs[t + 1] as stored, NaN included.
        let shared = t > 0
            && ep.next_obs[..(t - 1) * o]
                .iter()
                .zip(&ep.obs[o..])
                .all(|(a, b)| a.to_bits() == b.to_bits());
        out.push(u8::from(shared));
        put_f32s(&mut out, &ep.obs);
        if shared {
            put_f32s(&mut out, &ep.next_obs[(t - 1) * o..]);
        } else {
            put_f32s(&mut out, &ep.next_obs);
        }
        put_f32s(&mut out, &ep.action);
        put_f32s(&mut out, &ep.reward);
    }
    out
}

/// The evaluation in `bytes`.
pub fn decode_evaluation(bytes: &[u8]) -> Result<Evaluation, WireError> {
    let mut r = Reader::new(bytes);
    r.magic(EVALUATION_MAGIC, "evaluation")?;
    let fitness = r.f64("fitness")?;
    let n = r.u32("episode count")? as usize;
    let mut episodes = Vec::with_capacity(n.min(1024));
    for _ in 0..n {
        let t = r.u32("episode length")? as usize;
        let obs_dim = r.u32("observation width")? as usize;
        let act_dim = r.u32("action width")? as usize;
        let ret = r.f64("return")?;
        let truncated = r.flag("truncated")?;
        let terminated = (0..t)
            .map(|_| r.flag("terminal flags"))
            .collect::<Result<_, _>>()?;
        let shared = r.flag("layout")?;
        let obs = r.f32s(t * obs_dim, "observations")?;
        let next_obs = if shared {
            let mut next = obs[obs_dim.min(obs.len())..].to_vec();
            next.extend(r.f32s(obs_dim, "final observation")?);
            next
        } else {
            r.f32s(t * obs_dim, "next observations")?
        };
        let action = r.f32s(t * act_dim, "actions")?;
        let reward = r.f32s(t, "rewards")?;
        episodes.push(Episode {
            obs,
            action,
            reward,
            next_obs,
            terminated,
            ret,
            truncated,
            obs_dim,
            act_dim,
        });
    }
    r.end()?;
    Ok(Evaluation { fitness, episodes })
}

fn put_u32(out: &mut Vec<u8>, v: usize) {
    let v = u32::try_from(v).expect("counts on the wire fit 32 bits");
    out.extend_from_slice(&v.to_le_bytes());
}

fn put_f32s(out: &mut Vec<u8>, v: &[f32]) {
    for x in v {
        out.extend_from_slice(&x.to_le_bytes());
    }
}

/// A cursor over bytes that names the field it could not read.
struct Reader<'b> {
    bytes: &'b [u8],
    at: usize,
}

impl<'b> Reader<'b> {
    fn new(bytes: &'b [u8]) -> Self {
        Self { bytes, at: 0 }
    }

    fn take(&mut self, n: usize, what: &'static str) -> Result<&'b [u8], WireError> {
        let end = self
            .at
            .checked_add(n)
            .filter(|&e| e <= self.bytes.len())
            .ok_or(WireError::Truncated { what })?;
        let s = &self.bytes[self.at..end];
        self.at = end;
        Ok(s)
    }

    fn magic(&mut self, magic: &[u8; 4], expected: &'static str) -> Result<(), WireError> {
        let found = self.take(4, "tag")?;
        if found == magic {
            Ok(())
        } else {
            Err(WireError::Magic {
                expected,
                found: found.to_vec(),
            })
        }
    }

    fn u8(&mut self, what: &'static str) -> Result<u8, WireError> {
        Ok(self.take(1, what)?[0])
    }

    fn flag(&mut self, what: &'static str) -> Result<bool, WireError> {
        match self.u8(what)? {
            0 => Ok(false),
            1 => Ok(true),
            v => Err(WireError::Value {
                what,
                value: u64::from(v),
            }),
        }
    }

    fn u32(&mut self, what: &'static str) -> Result<u32, WireError> {
        let b = self.take(4, what)?;
        Ok(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    }

    fn u64(&mut self, what: &'static str) -> Result<u64, WireError> {
        let mut a = [0u8; 8];
        a.copy_from_slice(self.take(8, what)?);
        Ok(u64::from_le_bytes(a))
    }

    fn f64(&mut self, what: &'static str) -> Result<f64, WireError> {
        Ok(f64::from_bits(self.u64(what)?))
    }

    fn f32s(&mut self, n: usize, what: &'static str) -> Result<Vec<f32>, WireError> {
        let bytes = n
            .checked_mul(4)
            .ok_or(WireError::Truncated { what })
            .and_then(|len| self.take(len, what))?;
        Ok(bytes
            .chunks_exact(4)
            .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
            .collect())
    }

    fn end(&self) -> Result<(), WireError> {
        match self.bytes.len() - self.at {
            0 => Ok(()),
            n => Err(WireError::Trailing(n)),
        }
    }
}
