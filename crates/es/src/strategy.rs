//! The evolution strategy of the paper's §3.2 (eqs. 8–11) on flat parameter vectors.
//!
//! - eq. 8: individuals θ'ᵢ = θ + σ εᵢ, εᵢ ~ N(0, I);
//! - eq. 9: fitness Fᵢ = mean return over K rollouts (computed by the caller);
//! - eq. 10: θ ← Σⱼ wⱼ θⱼ over the Nₑ elites, best first, with the log-rank weights of CMA-ES
//!   and CEM-RL, wⱼ ∝ ln(Nₑ + 1) − ln j, normalised to sum to 1 (the paper does not give its
//!   weights; these favour better elites while keeping every elite's influence positive);
//! - eq. 11: σ ← (1 − λ) σ + λ σ_min.
//!
//! Noise is drawn from the stream [`Stream::Perturbation`] of (generation, individual), so the
//! population does not depend on which thread evaluates whom.

use esrl_streams::Stream;
use rand_distr::{Distribution, StandardNormal};
use serde::{Deserialize, Serialize};

/// Settings of the evolution strategy. Defaults are the paper's (§5) where it gives them and
/// MATLAB's `rlEvolutionStrategyTrainingOptions` where it does not.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct EsConfig {
    /// Individuals per generation N, the RL actor included. Default 25 (paper §5, MATLAB).
    pub population: usize,
    /// Share of the population kept as elites. Default 0.5 (MATLAB's `PercentageEliteSize` 50).
    pub elite_fraction: f64,
    /// Initial mutation scale σ. Default 0.25 (paper §5).
    pub sigma: f64,
    /// Floor σ decays toward, σ_min in eq. 11. Default 0.01 (esrl's choice: the paper gives
    /// none; a hundredth keeps perturbations meaningful for weights of order 0.05–0.1).
    pub sigma_min: f64,
    /// Decay rate λ of eq. 11. Default 0.01 (esrl's choice: σ halves its distance to σ_min in
    /// about 70 generations, so exploration lasts a good share of the paper's 1500).
    pub sigma_decay: f64,
    /// Rollouts per individual K in eq. 9. Default 1 (MATLAB's `EvaluationsPerIndividual`).
    pub evaluations: usize,
    /// How individuals act in the rollouts that score them. Default `auto` (ES-SAC samples,
    /// ES-TD3/ES-DDPG act deterministically), see [`Fitness`].
    pub fitness: Fitness,
    /// Order of replacement and inner training within a generation. Default
    /// `replace-then-train` (paper §5, SPEC §5), see [`LoopOrder`].
    pub order: LoopOrder,
}

/// How the individuals of a generation act in the rollouts that score them (`es.fitness`).
///
/// Every rollout an individual runs, scored or not, goes into the replay buffer.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Fitness {
    /// ES-SAC individuals sample their Gaussian policy (the paper: the genome includes the
    /// std head and α, and the buffer needs exploratory data); ES-TD3/ES-DDPG individuals act
    /// by tanh μ, their parameter noise being the exploration (as in CEM-RL).
    #[default]
    Auto,
    /// Every individual acts with its algorithm's exploration (SAC: a Gaussian sample;
    /// TD3/DDPG: tanh μ plus the exploration noise) and is scored on that rollout.
    Sampled,
    /// Every individual acts by tanh μ and is scored on that rollout: the fitness measures
    /// the policy that `esrl eval` would run, without the luck of the action noise.
    Deterministic,
    /// Each of the K evaluations is two rollouts from the same initial state: one with the
    /// algorithm's exploration (data for the buffer) and one by tanh μ (the score, its data
    /// kept too). Twice the environment steps.
    Both,
}

/// The order of elitist replacement and inner training in one generation (`es.order`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum LoopOrder {
    /// Replacement first, then the inner cycles refine the kept actor, which is individual 0
    /// of the next generation (paper §5; CEM-RL and ERL likewise evaluate the gradient-trained
    /// actor before anything can replace it).
    #[default]
    ReplaceThenTrain,
    /// The inner cycles train the RL actor first, then replacement (decided on fitnesses
    /// measured before that training) may overwrite it, discarding the updates unevaluated.
    /// An ablation switch: it measures what evaluating the trained actor is worth.
    TrainThenReplace,
}

impl Default for EsConfig {
    fn default() -> Self {
        Self {
            population: 25,
            elite_fraction: 0.5,
            sigma: 0.25,
            sigma_min: 0.01,
            sigma_decay: 0.01,
            evaluations: 1,
            fitness: Fitness::Auto,
            order: LoopOrder::ReplaceThenTrain,
        }
    }
}

/// A configuration value that cannot work, naming the field.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("es.{field} = {value}: {reason}")]
pub struct ConfigError {
    /// Field name inside `[es]`.
    pub field: &'static str,
    /// The offending value, as written.
    pub value: String,
    /// What a valid value looks like.
    pub reason: &'static str,
}

impl EsConfig {
    /// Checks every field, returning the first that cannot work.
    pub fn validate(&self) -> Result<(), ConfigError> {
        let err = |field, value: String, reason| {
            Err(ConfigError {
                field,
                value,
                reason,
            })
        };
        if self.population < 2 {
            return err(
                "population",
                self.population.to_string(),
                "needs at least 2 (the RL actor and one perturbation)",
            );
        }
        if !(self.elite_fraction > 0.0 && self.elite_fraction <= 1.0) {
            return err(
                "elite_fraction",
                self.elite_fraction.to_string(),
                "must be in (0, 1]",
            );
        }
        if !(self.sigma.is_finite() && self.sigma >= 0.0) {
            return err("sigma", self.sigma.to_string(), "must be finite and ≥ 0");
        }
        if !(self.sigma_min.is_finite() && self.sigma_min >= 0.0) {
            return err(
                "sigma_min",
                self.sigma_min.to_string(),
                "must be finite and ≥ 0",
            );
        }
        if !(self.sigma_decay >= 0.0 && self.sigma_decay <= 1.0) {
            return err(
                "sigma_decay",
                self.sigma_decay.to_string(),
                "must be in [0, 1]",
            );
        }
        if self.evaluations == 0 {
            return err("evaluations", "0".into(), "needs at least one rollout");
        }
        Ok(())
    }

    /// Number of elites Nₑ = round(N · share), at least 1.
    pub fn elites(&self) -> usize {
        ((self.population as f64 * self.elite_fraction).round() as usize).clamp(1, self.population)
    }
}

/// The distribution the ES samples from: mean θ and scale σ.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Strategy {
    /// Mean θ.
    pub mean: Vec<f32>,
    /// Current mutation scale σ.
    pub sigma: f64,
    /// Generations completed.
    pub generation: u64,
    /// The run seed the noise streams derive from.
    seed: u64,
}

/// Log-rank recombination weights for `n` elites, best first, summing to 1.
pub fn elite_weights(n: usize) -> Vec<f64> {
    let raw: Vec<f64> = (1..=n)
        .map(|j| ((n + 1) as f64).ln() - (j as f64).ln())
        .collect();
    let total: f64 = raw.iter().sum();
    raw.iter().map(|w| w / total).collect()
}

/// Indices of `fitness` sorted best first; ties keep the lower index first, NaN counts as worst.
pub fn rank(fitness: &[f64]) -> Vec<usize> {
    let mut idx: Vec<usize> = (0..fitness.len()).collect();
    let key = |i: usize| {
        if fitness[i].is_nan() {
            f64::NEG_INFINITY
        } else {
            fitness[i]
        }
    };
    idx.sort_by(|&a, &b| key(b).total_cmp(&key(a)).then(a.cmp(&b)));
    idx
}

impl Strategy {
    /// A strategy centred on `mean` with scale `sigma`; the run seed `seed` keys every noise
    /// stream.
    pub fn new(mean: Vec<f32>, sigma: f64, seed: u64) -> Self {
        Self {
            mean,
            sigma,
            generation: 0,
            seed,
        }
    }

    /// Individual `index` of the current generation (eq. 8): θ + σ ε with ε from its own stream.
    pub fn perturbation(&self, index: usize) -> Vec<f32> {
        let mut rng = Stream::Perturbation {
            generation: self.generation,
            index: index as u64,
        }
        .rng(self.seed);
        let sigma = self.sigma as f32;
        self.mean
            .iter()
            .map(|&m| {
                let e: f32 = StandardNormal.sample(&mut rng);
                m + sigma * e // eq. 8
            })
            .collect()
    }

    /// Eqs. 10 and 11: recombines the elites of `individuals` ranked by `fitness`, decays σ and
    /// advances the generation. Returns the ranking used, best first.
    pub fn update(
        &mut self,
        individuals: &[&[f32]],
        fitness: &[f64],
        cfg: &EsConfig,
    ) -> Vec<usize> {
        assert_eq!(
            individuals.len(),
            fitness.len(),
            "one fitness per individual"
        );
        let order = rank(fitness);
        let n_elite = cfg.elites().min(order.len());
        let weights = elite_weights(n_elite);
        let mut mean = vec![0.0f64; self.mean.len()];
        for (w, &i) in weights.iter().zip(&order[..n_elite]) {
            for (m, &x) in mean.iter_mut().zip(individuals[i]) {
                *m += w * f64::from(x);
            }
        }
        self.mean = mean.into_iter().map(|m| m as f32).collect(); // eq. 10
        self.sigma = (1.0 - cfg.sigma_decay) * self.sigma + cfg.sigma_decay * cfg.sigma_min; // eq. 11
        self.generation += 1;
        order
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn weights_match_hand_computation() {
        // n = 3: ln4 − ln1, ln4 − ln2, ln4 − ln3 = 1.386294, 0.693147, 0.287682; sum 2.367124.
        let w = elite_weights(3);
        let expect = [0.585_648, 0.292_824, 0.121_532];
        for (a, b) in w.iter().zip(expect) {
            assert!((a - b).abs() < 1e-5, "{a} vs {b}");
        }
        assert_eq!(elite_weights(1), vec![1.0]);
    }

    #[test]
    fn update_recombines_elites_and_decays_sigma() {
        let cfg = EsConfig {
            population: 4,
            elite_fraction: 0.5,
            sigma: 1.0,
            sigma_min: 0.1,
            sigma_decay: 0.5,
            ..EsConfig::default()
        };
        let mut s = Strategy::new(vec![0.0, 0.0], 1.0, 1);
        let a = [1.0f32, 2.0];
        let b = [3.0f32, -1.0];
        let c = [9.0f32, 9.0];
        let d = [-5.0f32, 0.0];
        let order = s.update(&[&a, &b, &c, &d], &[5.0, 7.0, f64::NAN, 1.0], &cfg);
        assert_eq!(order, vec![1, 0, 3, 2], "NaN ranks last");
        // Elites b then a: raw weights ln3 − ln1 = 1.0986 and ln3 − ln2 = 0.4055.
        let wb = 3f64.ln() / (3f64.ln() + 1.5f64.ln());
        let wa = 1.0 - wb;
        assert!((f64::from(s.mean[0]) - (wb * 3.0 + wa * 1.0)).abs() < 1e-6);
        assert!((f64::from(s.mean[1]) - (-wb + wa * 2.0)).abs() < 1e-6);
        assert!((s.sigma - 0.55).abs() < 1e-12, "σ = 0.5·1 + 0.5·0.1");
        assert_eq!(s.generation, 1);
    }

    #[test]
    fn perturbations_are_seeded_per_individual_and_scaled() {
        let s = Strategy::new(vec![1.0; 20_000], 0.25, 9);
        let p3 = s.perturbation(3);
        assert_eq!(p3, s.perturbation(3), "same stream, same noise");
        assert_ne!(p3, s.perturbation(4));
        let eps: Vec<f64> = p3.iter().map(|&x| f64::from(x - 1.0) / 0.25).collect();
        let mean = eps.iter().sum::<f64>() / eps.len() as f64;
        let var = eps.iter().map(|e| (e - mean).powi(2)).sum::<f64>() / eps.len() as f64;
        // Standard errors: 1/√20000 ≈ 0.007 for the mean, ≈ 0.01 for the variance.
        assert!(mean.abs() < 0.03, "mean {mean}");
        assert!((var - 1.0).abs() < 0.05, "variance {var}");
    }

    #[test]
    fn validation_names_the_field() {
        let bad = EsConfig {
            sigma: -1.0,
            ..EsConfig::default()
        };
        let e = bad.validate().unwrap_err();
        assert_eq!(e.field, "sigma");
        assert!(e.to_string().contains("es.sigma = -1"));
        let bad = EsConfig {
            population: 1,
            ..EsConfig::default()
        };
        assert_eq!(bad.validate().unwrap_err().field, "population");
        let bad = EsConfig {
            elite_fraction: f64::NAN,
            ..EsConfig::default()
        };
        assert_eq!(bad.validate().unwrap_err().field, "elite_fraction");
        assert!(EsConfig::default().validate().is_ok());
        assert_eq!(EsConfig::default().elites(), 13);
    }
}
