#!/usr/bin/env python3
"""PyTorch twin of `esrl_nn::bench::run`: forward + backward of the same networks on the same
shapes, single thread, so the two can be compared like with like.

  actor : obs -> Linear(256)+ReLU -> LSTM(100) -> mean Linear(A), std softplus(Linear(A))+1e-5,
          tanh-Gaussian sample (rsample) with the stable log-prob correction;
          loss = mean(log_prob - sum(action))                 [B sequences x T steps]
  critic: obs -> Linear(128)+ReLU, act -> Linear(128)+ReLU, concat -> LSTM(112) -> Linear(1);
          loss = MSE(q, y)
  mlp_* : the same with Linear 256x256 (ReLU) trunks and no LSTM, on B transitions.

Each figure: median of --reps timings (ms) after --warmup runs (the minimum in min_ms, and the median on-CPU
time of the thread, from /proc/thread-self/schedstat, in cpu_ms), torch.set_num_threads(1),
process pinned to one CPU. Prints one JSON object.

    python crates/nn/scripts/torch_nn_bench.py [--obs 43] [--act 6] [--batch 256] [--seq 8]
"""
import argparse
import json
import os
import statistics
import time


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--obs", type=int, default=43)
    ap.add_argument("--act", type=int, default=6)
    ap.add_argument("--batch", type=int, default=256)
    ap.add_argument("--seq", type=int, default=8)
    ap.add_argument("--reps", type=int, default=15)
    ap.add_argument("--warmup", type=int, default=3)
    a = ap.parse_args()
    os.environ["OMP_NUM_THREADS"] = "1"
    allowed = sorted(os.sched_getaffinity(0))
    os.sched_setaffinity(0, {allowed[-1]})
    import torch
    import torch.nn as nn
    import torch.nn.functional as F

    torch.set_num_threads(1)
    torch.set_num_interop_threads(1)
    torch.manual_seed(0)
    LOG2 = float(torch.log(torch.tensor(2.0)))
    HALF_LN_2PI = 0.5 * float(torch.log(torch.tensor(2 * torch.pi)))
    O, A, B, T = a.obs, a.act, a.batch, a.seq

    def squash(mu, std):
        eps = torch.randn_like(mu)
        u = mu + std * eps
        act = torch.tanh(u)
        logp = (-0.5 * eps.pow(2) - std.log() - HALF_LN_2PI).sum(-1)
        logp = logp - (2 * (LOG2 - u - F.softplus(-2 * u))).sum(-1)
        return act, logp

    class Actor(nn.Module):
        def __init__(self, recurrent):
            super().__init__()
            self.recurrent = recurrent
            if recurrent:
                self.fc = nn.Sequential(nn.Linear(O, 256), nn.ReLU())
                self.lstm = nn.LSTM(256, 100, batch_first=False)
                h = 100
            else:
                self.fc = nn.Sequential(nn.Linear(O, 256), nn.ReLU(), nn.Linear(256, 256), nn.ReLU())
                h = 256
            self.mu = nn.Linear(h, A)
            self.std = nn.Linear(h, A)

        def forward(self, obs):
            z = self.fc(obs)
            if self.recurrent:
                z, _ = self.lstm(z)
            return squash(self.mu(z), F.softplus(self.std(z)) + 1e-5)

    class Critic(nn.Module):
        def __init__(self, recurrent):
            super().__init__()
            self.recurrent = recurrent
            if recurrent:
                self.obs_fc = nn.Linear(O, 128)
                self.act_fc = nn.Linear(A, 128)
                self.lstm = nn.LSTM(256, 112, batch_first=False)
                self.out = nn.Linear(112, 1)
            else:
                self.net = nn.Sequential(nn.Linear(O + A, 256), nn.ReLU(), nn.Linear(256, 256), nn.ReLU(),
                                         nn.Linear(256, 1))

        def forward(self, obs, act):
            if self.recurrent:
                z = torch.cat([F.relu(self.obs_fc(obs)), F.relu(self.act_fc(act))], -1)
                z, _ = self.lstm(z)
                return self.out(z).squeeze(-1)
            return self.net(torch.cat([obs, act], -1)).squeeze(-1)

    def nparams(m):
        return sum(p.numel() for p in m.parameters())

    mins, cpus = {}, {}

    def thread_cpu_ns():
        try:
            with open("/proc/thread-self/schedstat") as f:
                return int(f.read().split()[0])
        except OSError:
            return None

    def timeit(fn, reps, warmup, name):
        for _ in range(warmup):
            fn()
        v, c = [], []
        for _ in range(reps):
            c0 = thread_cpu_ns()
            t0 = time.perf_counter()
            fn()
            v.append((time.perf_counter() - t0) * 1e3)
            c1 = thread_cpu_ns()
            if c0 is not None and c1 is not None:
                c.append((c1 - c0) / 1e6)
        mins[name] = round(min(v), 3)
        if len(c) == len(v):
            cpus[name] = round(statistics.median(c), 3)
        return statistics.median(v)

    res = {"bench": "torch_nn_fwd_bwd", "torch": torch.__version__, "obs_dim": O, "act_dim": A,
           "batch": B, "seq_len": T, "threads": 1}
    for rec, tag, shape in ((True, "", (T, B)), (False, "mlp_", (B,))):
        actor, critic = Actor(rec), Critic(rec)
        obs = torch.randn(*shape, O)
        act = torch.rand(*shape, A) * 2 - 1
        y = torch.randn(*shape)

        def actor_step():
            actor.zero_grad(set_to_none=True)
            act_, logp = actor(obs)
            (logp - act_.sum(-1)).mean().backward()

        def critic_step():
            critic.zero_grad(set_to_none=True)
            F.mse_loss(critic(obs, act), y).backward()

        k = 1 if rec else 5
        res[tag + "actor_params"] = nparams(actor)
        res[tag + "critic_params"] = nparams(critic)
        res[tag + "actor_ms"] = round(timeit(actor_step, a.reps * k, a.warmup * k, tag + "actor"), 3)
        res[tag + "critic_ms"] = round(timeit(critic_step, a.reps * k, a.warmup * k, tag + "critic"), 3)
    res["min_ms"] = mins
    res["cpu_ms"] = cpus
    print(json.dumps(res), flush=True)


if __name__ == "__main__":
    main()
