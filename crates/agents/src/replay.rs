//! Experience replay that keeps episodes intact and samples sequences for recurrent training.
//!
//! Transitions live in a ring of fixed capacity, in the order they were pushed; each slot also
//! remembers which episode it belongs to and its index inside that episode. A recurrent batch
//! is `B` windows of `W = burn_in + seq_len` consecutive steps of ONE episode, laid out so that
//! the training part is always the last `seq_len` steps of the window:
//!
//! ```text
//! t:       0 .. burn_in-1 | burn_in .. W-1
//! role:    burn-in (mask 0) | trained (mask 1, or 0 past the episode's end)
//! ```
//!
//! The training start is drawn uniformly over every stored transition, so each transition is
//! the first trained step of a window with equal probability. Where the episode begins less
//! than `burn_in` steps before the training start, the window is left-padded with zeros and
//! `reset` marks the episode's first real step: the networks zero their (h, c) there, exactly
//! as a rollout starts from a zero state. Where the episode ends less than `seq_len` steps
//! after the start, the window is right-padded and `mask` is 0 on the padding. So a window
//! never mixes two episodes, burn-in reproduces the recurrent state the policy would have had
//! (up to the policy having changed since), and terminal transitions are sampled as often as
//! any other.
//!
//! Feed-forward agents draw single transitions (`W = 1`) from the same buffer.

use esrl_nn::{load_tensors, save_tensors, NamedTensor, NnError};
use rand::Rng;
use serde::{Deserialize, Serialize};
use std::collections::HashMap;
use std::path::Path;

/// One transition as the environment produced it.
#[derive(Debug, Clone, Copy)]
pub struct Transition<'a> {
    /// Observation the action was taken in, length `obs_dim`.
    pub obs: &'a [f32],
    /// Action taken, each entry in [-1, 1], length `act_dim`.
    pub action: &'a [f32],
    /// Reward received.
    pub reward: f32,
    /// Observation after the step, length `obs_dim`.
    pub next_obs: &'a [f32],
    /// The episode ended in a terminal state (a fall): no bootstrapping past it.
    pub terminated: bool,
}

/// A batch of `batch` windows of `window` steps. Every array is time-major, `(W, B, ...)`: row
/// `t * batch + b` holds step `t` of window `b`, the layout the LSTM consumes.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SequenceBatch {
    /// Number of windows `B`.
    pub batch: usize,
    /// Steps per window `W = burn_in + seq_len`.
    pub window: usize,
    /// Leading steps of each window that only warm up the recurrent state.
    pub burn_in: usize,
    /// Observations `(W, B, obs_dim)`.
    pub obs: Vec<f32>,
    /// Actions `(W, B, act_dim)`.
    pub action: Vec<f32>,
    /// Rewards `(W, B)`.
    pub reward: Vec<f32>,
    /// Next observations `(W, B, obs_dim)`.
    pub next_obs: Vec<f32>,
    /// 1.0 where the step ended the episode in a terminal state, else 0.0; `(W, B)`.
    pub terminated: Vec<f32>,
    /// 1.0 on real trained steps, 0.0 on burn-in and padding; `(W, B)`.
    pub mask: Vec<f32>,
    /// True where the recurrent state must be zeroed before the step; `(W, B)`.
    pub reset: Vec<bool>,
    /// The smallest and largest reward stored in the buffer when the batch was drawn
    /// ((0, 0) for an empty buffer): the bounds of `rl.clip_targets`.
    pub reward_range: (f32, f32),
}

impl SequenceBatch {
    /// Row of step `t` of window `b` in the time-major arrays.
    pub fn row(&self, t: usize, b: usize) -> usize {
        t * self.batch + b
    }

    /// Number of trained (mask 1) steps in the batch.
    pub fn trained_steps(&self) -> usize {
        self.mask.iter().filter(|&&m| m > 0.0).count()
    }
}

/// Ring buffer of transitions that knows episode boundaries.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct ReplayBuffer {
    obs_dim: usize,
    act_dim: usize,
    capacity: usize,
    /// Slots filled so far (≤ capacity).
    len: usize,
    /// Slot the next push writes.
    head: usize,
    /// Id given to the next episode started.
    next_episode: u64,
    /// Whether the last pushed transition ended its episode.
    episode_open: bool,
    /// Transitions pushed since creation (the incremental checkpoints count from it).
    #[serde(default)]
    pushed: u64,
    obs: Vec<f32>,
    action: Vec<f32>,
    reward: Vec<f32>,
    next_obs: Vec<f32>,
    terminated: Vec<bool>,
    episode: Vec<u64>,
    step: Vec<u32>,
    /// The smallest and largest stored reward ((0, 0) while empty), kept up to date by
    /// [`ReplayBuffer::push`] (rescanned only when an extreme is overwritten).
    #[serde(skip)]
    reward_range: (f32, f32),
}

impl ReplayBuffer {
    /// An empty buffer holding at most `capacity` transitions.
    pub fn new(obs_dim: usize, act_dim: usize, capacity: usize) -> Self {
        Self {
            obs_dim,
            act_dim,
            capacity,
            len: 0,
            head: 0,
            next_episode: 0,
            episode_open: false,
            pushed: 0,
            obs: vec![0.0; capacity * obs_dim],
            action: vec![0.0; capacity * act_dim],
            reward: vec![0.0; capacity],
            next_obs: vec![0.0; capacity * obs_dim],
            terminated: vec![false; capacity],
            episode: vec![0; capacity],
            step: vec![0; capacity],
            reward_range: (0.0, 0.0),
        }
    }

    /// The smallest and largest reward stored, `None` while the buffer is empty.
    pub fn reward_range(&self) -> Option<(f32, f32)> {
        (self.len > 0).then_some(self.reward_range)
    }

    /// Rescans the stored rewards for their range.
    fn rescan_reward_range(&mut self) {
        let stored = &self.reward[..self.len];
        self.reward_range = match stored.first() {
            None => (0.0, 0.0),
            Some(&r0) => stored
                .iter()
                .fold((r0, r0), |(lo, hi), &r| (lo.min(r), hi.max(r))),
        };
    }

    /// Transitions stored.
    pub fn len(&self) -> usize {
        self.len
    }

    /// True when nothing is stored.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Maximum number of transitions kept; older ones are overwritten.
    pub fn capacity(&self) -> usize {
        self.capacity
    }

    /// Observation size.
    pub fn obs_dim(&self) -> usize {
        self.obs_dim
    }

    /// Action size.
    pub fn act_dim(&self) -> usize {
        self.act_dim
    }

    /// Marks the end of the current episode (after a terminal or truncated step); the next push
    /// starts a new one.
    pub fn end_episode(&mut self) {
        self.episode_open = false;
    }

    /// Appends one transition to the current episode, starting a new episode if the previous
    /// one was ended with [`ReplayBuffer::end_episode`].
    ///
    /// # Panics
    /// If the slices do not have the buffer's dimensions (a programming error, not user input).
    pub fn push(&mut self, t: Transition<'_>) {
        assert_eq!(t.obs.len(), self.obs_dim, "obs length");
        assert_eq!(t.next_obs.len(), self.obs_dim, "next_obs length");
        assert_eq!(t.action.len(), self.act_dim, "action length");
        if self.capacity == 0 {
            return;
        }
        let prev = (self.head + self.capacity - 1) % self.capacity;
        let step = if self.episode_open && self.len > 0 {
            self.step[prev] + 1
        } else {
            self.next_episode += 1;
            0
        };
        let i = self.head;
        let overwritten = (self.len == self.capacity).then(|| self.reward[i]);
        let (o, a) = (self.obs_dim, self.act_dim);
        self.obs[i * o..(i + 1) * o].copy_from_slice(t.obs);
        self.next_obs[i * o..(i + 1) * o].copy_from_slice(t.next_obs);
        self.action[i * a..(i + 1) * a].copy_from_slice(t.action);
        self.reward[i] = t.reward;
        self.terminated[i] = t.terminated;
        self.episode[i] = self.next_episode;
        self.step[i] = step;
        self.episode_open = true;
        self.head = (self.head + 1) % self.capacity;
        self.len = (self.len + 1).min(self.capacity);
        self.pushed += 1;
        let (lo, hi) = self.reward_range;
        match overwritten {
            Some(old) if old <= lo || old >= hi => self.rescan_reward_range(),
            _ if self.len == 1 => self.reward_range = (t.reward, t.reward),
            _ => self.reward_range = (lo.min(t.reward), hi.max(t.reward)),
        }
    }

    /// Slot of the oldest stored transition.
    fn oldest(&self) -> usize {
        if self.len < self.capacity {
            0
        } else {
            self.head
        }
    }

    /// Slot `k` positions after slot `i` in push order, if it is stored.
    fn offset(&self, i: usize, k: isize) -> Option<usize> {
        let age = (i + self.capacity - self.oldest()) % self.capacity;
        let target = age as isize + k;
        if target < 0 || target >= self.len as isize {
            return None;
        }
        Some((self.oldest() + target as usize) % self.capacity)
    }

    /// Draws `batch` windows of `burn_in + seq_len` steps (see the module docs).
    ///
    /// Returns an empty batch when the buffer is empty.
    pub fn sample_sequences<R: Rng + ?Sized>(
        &self,
        rng: &mut R,
        batch: usize,
        seq_len: usize,
        burn_in: usize,
    ) -> SequenceBatch {
        let window = burn_in + seq_len;
        let (o, a) = (self.obs_dim, self.act_dim);
        let mut out = SequenceBatch {
            batch,
            window,
            burn_in,
            obs: vec![0.0; batch * window * o],
            action: vec![0.0; batch * window * a],
            reward: vec![0.0; batch * window],
            next_obs: vec![0.0; batch * window * o],
            terminated: vec![0.0; batch * window],
            mask: vec![0.0; batch * window],
            reset: vec![false; batch * window],
            reward_range: self.reward_range,
        };
        if self.is_empty() || window == 0 {
            out.batch = 0;
            out.obs.clear();
            out.action.clear();
            out.reward.clear();
            out.next_obs.clear();
            out.terminated.clear();
            out.mask.clear();
            out.reset.clear();
            return out;
        }
        for b in 0..batch {
            let start = (self.oldest() + rng.random_range(0..self.len)) % self.capacity;
            let ep = self.episode[start];
            let mut first_real = true;
            for t in 0..window {
                let k = t as isize - burn_in as isize;
                let Some(i) = self.offset(start, k).filter(|&i| self.episode[i] == ep) else {
                    continue;
                };
                let row = t * batch + b;
                out.obs[row * o..(row + 1) * o].copy_from_slice(&self.obs[i * o..(i + 1) * o]);
                out.next_obs[row * o..(row + 1) * o]
                    .copy_from_slice(&self.next_obs[i * o..(i + 1) * o]);
                out.action[row * a..(row + 1) * a]
                    .copy_from_slice(&self.action[i * a..(i + 1) * a]);
                out.reward[row] = self.reward[i];
                out.terminated[row] = f32::from(u8::from(self.terminated[i]));
                out.mask[row] = if t >= burn_in { 1.0 } else { 0.0 };
                // The state restarts at the first real step of the window: from zero at an
                // episode's first step, otherwise (the episode began before the window was
                // truncated by the ring's oldest slot) from zero as the best available guess.
                out.reset[row] = first_real;
                first_real = false;
            }
        }
        out
    }

    /// Draws `batch` single transitions uniformly (feed-forward agents): a window of one step.
    pub fn sample_transitions<R: Rng + ?Sized>(&self, rng: &mut R, batch: usize) -> SequenceBatch {
        self.sample_sequences(rng, batch, 1, 0)
    }

    /// Transitions pushed since the buffer was created (stored or since overwritten).
    pub fn pushed(&self) -> u64 {
        self.pushed
    }

    /// Saves the stored transitions, oldest first, as F32 safetensors (episode structure is
    /// kept through each slot's step index; only the filled part is written).
    pub fn save(&self, path: &Path) -> Result<(), NnError> {
        self.save_last(path, self.len)
    }

    /// Saves, in the format of [`ReplayBuffer::save`], the transitions pushed since the
    /// buffer had seen `since` pushes and still stored (the newest `pushed − since`, at most
    /// the whole buffer): one chunk of an incremental checkpoint. Returns how many it wrote.
    pub fn save_since(&self, path: &Path, since: u64) -> Result<usize, NnError> {
        let n = usize::try_from(self.pushed.saturating_sub(since))
            .unwrap_or(usize::MAX)
            .min(self.len);
        self.save_last(path, n)?;
        Ok(n)
    }

    /// Saves the newest `n` stored transitions, oldest first.
    fn save_last(&self, path: &Path, n: usize) -> Result<(), NnError> {
        let skip = self.len - n;
        let order: Vec<usize> = (skip..self.len)
            .map(|k| (self.oldest() + k) % self.capacity)
            .collect();
        let gather = |src: &[f32], w: usize| -> Vec<f32> {
            order
                .iter()
                .flat_map(|&i| src[i * w..(i + 1) * w].iter().copied())
                .collect()
        };
        let tensors = vec![
            NamedTensor {
                name: "obs".into(),
                shape: vec![n, self.obs_dim],
                data: gather(&self.obs, self.obs_dim),
            },
            NamedTensor {
                name: "action".into(),
                shape: vec![n, self.act_dim],
                data: gather(&self.action, self.act_dim),
            },
            NamedTensor {
                name: "reward".into(),
                shape: vec![n],
                data: gather(&self.reward, 1),
            },
            NamedTensor {
                name: "next_obs".into(),
                shape: vec![n, self.obs_dim],
                data: gather(&self.next_obs, self.obs_dim),
            },
            NamedTensor {
                name: "terminated".into(),
                shape: vec![n],
                data: order
                    .iter()
                    .map(|&i| f32::from(u8::from(self.terminated[i])))
                    .collect(),
            },
            NamedTensor {
                name: "step".into(),
                shape: vec![n],
                data: order.iter().map(|&i| self.step[i] as f32).collect(),
            },
        ];
        let mut meta = HashMap::new();
        meta.insert("capacity".to_string(), self.capacity.to_string());
        meta.insert("episode_open".to_string(), self.episode_open.to_string());
        save_tensors(path, &tensors, Some(meta))
    }

    /// Loads a buffer written by [`ReplayBuffer::save`] into a buffer of the given shape.
    /// Sampling from the loaded buffer draws exactly what the saved one would have drawn.
    pub fn load(
        path: &Path,
        obs_dim: usize,
        act_dim: usize,
        capacity: usize,
        episode_open: bool,
    ) -> Result<Self, NnError> {
        let chunk = Chunk::read(path, obs_dim, act_dim)?;
        if chunk.len() > capacity {
            return Err(NnError::ShapeMismatch {
                path: path.to_path_buf(),
                name: "obs".into(),
                expected: vec![capacity, obs_dim],
                found: vec![chunk.len(), obs_dim],
            });
        }
        let pushed = chunk.len() as u64;
        Ok(Self::from_chunks(
            vec![chunk],
            obs_dim,
            act_dim,
            capacity,
            episode_open,
            pushed,
        ))
    }

    /// Loads a buffer from the chunks of an incremental checkpoint
    /// ([`ReplayBuffer::save_since`]), oldest first, keeping the newest `capacity`
    /// transitions; `pushed` is the buffer's push count when the last chunk was written.
    /// Sampling from the loaded buffer draws exactly what the saved one would have drawn.
    pub fn load_chunks(
        paths: &[&Path],
        obs_dim: usize,
        act_dim: usize,
        capacity: usize,
        episode_open: bool,
        pushed: u64,
    ) -> Result<Self, NnError> {
        let chunks = paths
            .iter()
            .map(|p| Chunk::read(p, obs_dim, act_dim))
            .collect::<Result<Vec<_>, _>>()?;
        Ok(Self::from_chunks(
            chunks,
            obs_dim,
            act_dim,
            capacity,
            episode_open,
            pushed,
        ))
    }

    fn from_chunks(
        chunks: Vec<Chunk>,
        obs_dim: usize,
        act_dim: usize,
        capacity: usize,
        episode_open: bool,
        pushed: u64,
    ) -> Self {
        let total: usize = chunks.iter().map(Chunk::len).sum();
        let n = total.min(capacity);
        let mut skip = total - n;
        let mut buf = Self::new(obs_dim, act_dim, capacity);
        let mut i = 0;
        let mut id = 0u64;
        for c in &chunks {
            for k in 0..c.len() {
                if skip > 0 {
                    skip -= 1;
                    continue;
                }
                buf.obs[i * obs_dim..(i + 1) * obs_dim]
                    .copy_from_slice(&c.obs[k * obs_dim..(k + 1) * obs_dim]);
                buf.next_obs[i * obs_dim..(i + 1) * obs_dim]
                    .copy_from_slice(&c.next_obs[k * obs_dim..(k + 1) * obs_dim]);
                buf.action[i * act_dim..(i + 1) * act_dim]
                    .copy_from_slice(&c.action[k * act_dim..(k + 1) * act_dim]);
                buf.reward[i] = c.reward[k];
                buf.terminated[i] = c.terminated[k] != 0.0;
                buf.step[i] = c.step[k] as u32;
                if i == 0 || buf.step[i] == 0 {
                    id += 1;
                }
                buf.episode[i] = id;
                i += 1;
            }
        }
        buf.len = n;
        buf.head = n % capacity.max(1);
        buf.next_episode = id;
        buf.episode_open = episode_open && n > 0;
        buf.pushed = pushed;
        buf.rescan_reward_range();
        buf
    }

    /// Whether the last pushed transition's episode is still open (for checkpoints).
    pub fn episode_open(&self) -> bool {
        self.episode_open
    }

    /// Index of slot `i` inside its episode (tests and diagnostics).
    pub fn episode_step(&self, i: usize) -> u32 {
        self.step[i]
    }
}

/// The arrays of one saved file (whole buffer or incremental chunk), oldest first.
struct Chunk {
    obs: Vec<f32>,
    action: Vec<f32>,
    reward: Vec<f32>,
    next_obs: Vec<f32>,
    terminated: Vec<f32>,
    step: Vec<f32>,
}

impl Chunk {
    fn len(&self) -> usize {
        self.reward.len()
    }

    /// Reads a file written by [`ReplayBuffer::save`] or [`ReplayBuffer::save_since`],
    /// checking every array's shape against the others and the buffer's widths.
    fn read(path: &Path, obs_dim: usize, act_dim: usize) -> Result<Self, NnError> {
        let mut file = load_tensors(path)?;
        let mut take = |name: &str| -> Result<NamedTensor, NnError> {
            file.remove(name).ok_or_else(|| NnError::MissingTensor {
                path: path.to_path_buf(),
                name: name.into(),
            })
        };
        let (obs, action, reward) = (take("obs")?, take("action")?, take("reward")?);
        let (next_obs, terminated, step) = (take("next_obs")?, take("terminated")?, take("step")?);
        let n = reward.data.len();
        for (t, width) in [
            (&obs, obs_dim),
            (&action, act_dim),
            (&reward, 1),
            (&next_obs, obs_dim),
            (&terminated, 1),
            (&step, 1),
        ] {
            if t.data.len() != n * width {
                return Err(NnError::ShapeMismatch {
                    path: path.to_path_buf(),
                    name: t.name.clone(),
                    expected: vec![n, width],
                    found: t.shape.clone(),
                });
            }
        }
        Ok(Self {
            obs: obs.data,
            action: action.data,
            reward: reward.data,
            next_obs: next_obs.data,
            terminated: terminated.data,
            step: step.data,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    /// Pushes episodes whose observation encodes (episode, step) so windows can be checked.
    fn filled(lengths: &[usize], capacity: usize) -> ReplayBuffer {
        let mut buf = ReplayBuffer::new(2, 1, capacity);
        for (e, &n) in lengths.iter().enumerate() {
            for s in 0..n {
                // Episode ids start at 1 so that a zero observation marks padding.
                let obs = [(e + 1) as f32, s as f32];
                let next = [(e + 1) as f32, (s + 1) as f32];
                buf.push(Transition {
                    obs: &obs,
                    action: &[s as f32],
                    reward: 1.0,
                    next_obs: &next,
                    terminated: s + 1 == n && e % 2 == 0,
                });
            }
            buf.end_episode();
        }
        buf
    }

    #[test]
    fn windows_stay_inside_one_episode_and_are_consecutive() {
        let buf = filled(&[3, 20, 1, 7, 12], 1000);
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        let batch = buf.sample_sequences(&mut rng, 500, 4, 3);
        for b in 0..batch.batch {
            let real: Vec<(f32, f32)> = (0..batch.window)
                .map(|t| batch.row(t, b))
                .filter(|&r| batch.obs[r * 2] != 0.0)
                .map(|r| (batch.obs[r * 2], batch.obs[r * 2 + 1]))
                .collect();
            assert!(!real.is_empty());
            for pair in real.windows(2) {
                assert_eq!(pair[1].0, pair[0].0, "window mixes episodes");
                assert_eq!(pair[1].1, pair[0].1 + 1.0, "steps not consecutive");
            }
        }
    }

    #[test]
    fn burn_in_is_left_padded_and_reset_marks_the_first_real_step() {
        // One episode of 10 steps: a training start at step 1 with burn-in 3 has one real
        // burn-in step (step 0), preceded by two padded steps.
        let buf = filled(&[10], 100);
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let batch = buf.sample_sequences(&mut rng, 400, 2, 3);
        let mut seen = false;
        for b in 0..batch.batch {
            let col = |v: &[bool]| -> Vec<bool> {
                (0..batch.window).map(|t| v[batch.row(t, b)]).collect()
            };
            let mask: Vec<f32> = (0..batch.window)
                .map(|t| batch.mask[batch.row(t, b)])
                .collect();
            let step = |t: usize| batch.obs[batch.row(t, b) * 2 + 1];
            let first_trained = step(3);
            if first_trained == 1.0 {
                seen = true;
                assert_eq!(col(&batch.reset), [false, false, true, false, false]);
                assert_eq!(mask, [0.0, 0.0, 0.0, 1.0, 1.0]);
                assert_eq!(step(2), 0.0, "real burn-in step is step 0");
            }
            // Exactly one reset per window, at the first real step.
            let resets = col(&batch.reset).iter().filter(|&&r| r).count();
            assert_eq!(resets, 1);
        }
        assert!(seen, "a window starting at step 1 should have been drawn");
    }

    #[test]
    fn windows_past_the_episode_end_are_masked() {
        let buf = filled(&[2], 10);
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let batch = buf.sample_sequences(&mut rng, 50, 4, 0);
        for b in 0..batch.batch {
            let start = batch.obs[batch.row(0, b) * 2 + 1] as usize;
            let mask: Vec<f32> = (0..4).map(|t| batch.mask[batch.row(t, b)]).collect();
            let expect: Vec<f32> = (0..4)
                .map(|t| if start + t < 2 { 1.0 } else { 0.0 })
                .collect();
            assert_eq!(mask, expect);
        }
        // Terminal flag of the last step survives.
        assert!(batch.terminated.contains(&1.0));
    }

    #[test]
    fn ring_overwrites_oldest_and_never_joins_across_the_seam() {
        let buf = filled(&[6, 6, 6], 10);
        assert_eq!(buf.len(), 10);
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        let batch = buf.sample_sequences(&mut rng, 300, 3, 2);
        for b in 0..batch.batch {
            let eps: Vec<f32> = (0..batch.window)
                .filter(|&t| batch.mask[batch.row(t, b)] > 0.0)
                .map(|t| batch.obs[batch.row(t, b) * 2])
                .collect();
            assert!(eps.windows(2).all(|w| w[0] == w[1]));
            assert!(
                eps.iter().all(|&e| e >= 2.0),
                "the first episode was partly overwritten"
            );
        }
    }

    #[test]
    fn save_and_load_sample_identically() {
        let buf = filled(&[6, 6, 6], 10);
        let dir = std::env::temp_dir().join(format!("esrl-replay-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("replay.safetensors");
        buf.save(&path).unwrap();
        let back = ReplayBuffer::load(&path, 2, 1, 10, buf.episode_open()).unwrap();
        let a = buf.sample_sequences(&mut ChaCha8Rng::seed_from_u64(2), 64, 3, 2);
        let b = back.sample_sequences(&mut ChaCha8Rng::seed_from_u64(2), 64, 3, 2);
        assert_eq!(a, b);
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn incremental_chunks_load_like_the_whole_buffer() {
        let dir = tempfile::tempdir().unwrap();
        let mut buf = filled(&[6, 6, 6], 25);
        let c1 = dir.path().join("c1.safetensors");
        assert_eq!(buf.save_since(&c1, 0).unwrap(), 18);
        let mark = buf.pushed();
        // Wrap the ring: 14 more transitions, 7 of the first chunk's are overwritten.
        for s in 0..14 {
            let obs = [9.0, s as f32];
            buf.push(Transition {
                obs: &obs,
                action: &[0.5],
                reward: 2.0,
                next_obs: &obs,
                terminated: false,
            });
        }
        let c2 = dir.path().join("c2.safetensors");
        assert_eq!(buf.save_since(&c2, mark).unwrap(), 14);
        let back = ReplayBuffer::load_chunks(
            &[c1.as_path(), c2.as_path()],
            2,
            1,
            25,
            buf.episode_open(),
            buf.pushed(),
        )
        .unwrap();
        assert_eq!(back.len(), 25);
        assert_eq!(back.pushed(), 32);
        for seed in 0..4 {
            let a = buf.sample_sequences(&mut ChaCha8Rng::seed_from_u64(seed), 64, 3, 2);
            let b = back.sample_sequences(&mut ChaCha8Rng::seed_from_u64(seed), 64, 3, 2);
            assert_eq!(a, b, "seed {seed}");
        }
        // More pushed since the mark than the buffer holds: the chunk is the whole buffer.
        let c3 = dir.path().join("c3.safetensors");
        assert_eq!(buf.save_since(&c3, 0).unwrap(), 25);
    }

    #[test]
    fn sampling_is_deterministic_for_a_seed() {
        let buf = filled(&[30, 40], 100);
        let a = buf.sample_sequences(&mut ChaCha8Rng::seed_from_u64(5), 16, 4, 4);
        let b = buf.sample_sequences(&mut ChaCha8Rng::seed_from_u64(5), 16, 4, 4);
        assert_eq!(a, b);
    }

    #[test]
    fn reward_range_follows_the_stored_rewards() {
        // Few distinct values, so extremes repeat and are overwritten while a copy remains.
        let mut rng = ChaCha8Rng::seed_from_u64(8);
        let mut buf = ReplayBuffer::new(1, 1, 7);
        let mut pushed: Vec<f32> = Vec::new();
        assert_eq!(buf.reward_range(), None);
        for k in 0..300 {
            let reward = f32::from(rng.random_range(-3i8..=3)) * 0.5;
            buf.push(Transition {
                obs: &[k as f32],
                action: &[0.0],
                reward,
                next_obs: &[k as f32],
                terminated: false,
            });
            pushed.push(reward);
            let stored = &pushed[pushed.len().saturating_sub(7)..];
            let lo = stored.iter().copied().fold(f32::INFINITY, f32::min);
            let hi = stored.iter().copied().fold(f32::NEG_INFINITY, f32::max);
            assert_eq!(buf.reward_range(), Some((lo, hi)), "after push {k}");
        }
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("b.safetensors");
        buf.save(&path).unwrap();
        let back = ReplayBuffer::load(&path, 1, 1, 7, false).unwrap();
        assert_eq!(back.reward_range(), buf.reward_range());
        let batch = back.sample_transitions(&mut rng, 4);
        assert_eq!(Some(batch.reward_range), buf.reward_range());
    }
}
