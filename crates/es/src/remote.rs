//! Evaluating in other processes: both ends of a remote evaluator, with a [`Transport`] of
//! bytes between them.
//!
//! The driver's [`WireEvaluator`] encodes each genome of a generation ([`crate::wire`]),
//! hands the bytes to its transport (a Ray cluster, a process pool, a socket) and decodes the
//! evaluations that come back. On the other side a [`Worker`] turns genome bytes into
//! evaluation bytes with [`rollout_genome`] on a fresh environment, exactly as
//! [`LocalEvaluator`](crate::LocalEvaluator) does, so the run computes the same thing
//! wherever its genomes go. The worker's policy comes from the run's configuration (same
//! architecture and exploration); each genome brings its own weights and seeds.
//!
//! [`Traffic`] counts what crossed: genomes, bytes out, bytes in.

use crate::evaluate::{rollout_genome, Evaluation, Evaluator, Generation};
use crate::wire::{decode_evaluation, decode_genome, encode_evaluation, encode_genome};
use esrl_agents::{AgentError, Policy};
use esrl_sim::MakeEnv;
use std::fmt;
use std::sync::{Arc, Mutex};

/// Carries genome bytes to workers and their evaluation bytes back.
pub trait Transport: Send + Sync + fmt::Debug {
    /// Rolls out every genome (encoded by [`crate::encode_genome`]) and returns one encoded
    /// evaluation per genome, in the order given. An error is a message for the user.
    fn roll_out(&self, genomes: Vec<Vec<u8>>) -> Result<Vec<Vec<u8>>, String>;
}

/// What a [`WireEvaluator`] has moved so far.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Traffic {
    /// Calls to the transport (a pipelined generation makes two).
    pub calls: u64,
    /// Genomes sent.
    pub genomes: u64,
    /// Bytes of genomes sent.
    pub bytes_out: u64,
    /// Bytes of evaluations received.
    pub bytes_in: u64,
}

/// An [`Evaluator`] that sends genomes through a [`Transport`] as bytes.
#[derive(Debug)]
pub struct WireEvaluator<T> {
    transport: T,
    traffic: Mutex<Traffic>,
}

impl<T: Transport> WireEvaluator<T> {
    /// An evaluator over `transport`.
    pub fn new(transport: T) -> Self {
        Self {
            transport,
            traffic: Mutex::new(Traffic::default()),
        }
    }

    /// What has crossed the transport so far.
    pub fn traffic(&self) -> Traffic {
        *self.traffic.lock().unwrap_or_else(|e| e.into_inner())
    }
}

impl<T: Transport> Evaluator for WireEvaluator<T> {
    fn evaluate(&self, generation: &Generation) -> Result<Vec<Evaluation>, AgentError> {
        let out: Vec<Vec<u8>> = generation.genomes.iter().map(encode_genome).collect();
        let bytes_out: usize = out.iter().map(Vec::len).sum();
        let n = out.len();
        let back = self
            .transport
            .roll_out(out)
            .map_err(|e| remote_error(generation.index, e))?;
        if back.len() != n {
            return Err(remote_error(
                generation.index,
                format!("{} evaluations came back for {n} genomes", back.len()),
            ));
        }
        let bytes_in: usize = back.iter().map(Vec::len).sum();
        {
            let mut t = self.traffic.lock().unwrap_or_else(|e| e.into_inner());
            t.calls += 1;
            t.genomes += n as u64;
            t.bytes_out += bytes_out as u64;
            t.bytes_in += bytes_in as u64;
        }
        back.iter()
            .zip(&generation.genomes)
            .map(|(bytes, genome)| {
                decode_evaluation(bytes).map_err(|e| {
                    remote_error(
                        generation.index,
                        format!("the evaluation of individual {}: {e}", genome.index),
                    )
                })
            })
            .collect()
    }
}

fn remote_error(generation: usize, reason: String) -> AgentError {
    AgentError::State {
        field: format!("remote evaluation of generation {generation}"),
        reason,
    }
}

/// The worker side: rolls genome bytes out and returns evaluation bytes.
pub struct Worker {
    make_env: Arc<MakeEnv>,
    policy: Policy,
}

impl fmt::Debug for Worker {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Worker")
            .field("params", &esrl_nn::Module::num_params(self.policy.actor()))
            .finish()
    }
}

impl Worker {
    /// A worker acting with `policy`'s architecture and exploration (each genome's weights
    /// replace its own) on environments from `make_env`.
    pub fn new(make_env: Arc<MakeEnv>, policy: Policy) -> Self {
        Self { make_env, policy }
    }

    /// Rolls the genome in `genome` out on a fresh environment and returns its evaluation
    /// as bytes. Bad bytes and genomes that do not fit the policy are errors.
    pub fn rollout(&self, genome: &[u8]) -> Result<Vec<u8>, AgentError> {
        let genome = decode_genome(genome).map_err(|e| AgentError::State {
            field: "genome bytes".into(),
            reason: e.to_string(),
        })?;
        let mut env = (self.make_env)();
        let evaluation = rollout_genome(&self.policy, &genome, env.as_mut())?;
        Ok(encode_evaluation(&evaluation))
    }
}
