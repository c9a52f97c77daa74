#!/usr/bin/env python3
"""Recomputes, in PyTorch, what examples/torch_parity_export.rs wrote: loads the esrl-nn
checkpoint into torch modules (nn.Linear / nn.LSTM with bias_ih = bias, bias_hh = 0), runs the
same forward and loss, and compares outputs and gradients. Also prints the PyTorch values that
tests/torch_parity.rs pastes.

    cargo run --release -p esrl-nn --example torch_parity_export -- /tmp/parity.safetensors
    python crates/nn/scripts/torch_parity.py /tmp/parity.safetensors
"""
import math
import sys

import torch
import torch.nn as nn
import torch.nn.functional as F
from safetensors.torch import load_file

T, B = 4, 2
t = load_file(sys.argv[1] if len(sys.argv) > 1 else "torch_parity.safetensors")
torch.set_default_dtype(torch.float64)  # reference in f64
t = {k: v.double() for k, v in t.items()}


def lstm(prefix, inp, hidden):
    m = nn.LSTM(inp, hidden)
    with torch.no_grad():
        m.weight_ih_l0.copy_(t[prefix + "lstm.weight_ih"])
        m.weight_hh_l0.copy_(t[prefix + "lstm.weight_hh"])
        m.bias_ih_l0.copy_(t[prefix + "lstm.bias"])
        m.bias_hh_l0.zero_()
    return m


def linear(prefix, name):
    w = t[f"{prefix}{name}.weight"]
    m = nn.Linear(w.shape[1], w.shape[0])
    with torch.no_grad():
        m.weight.copy_(w)
        m.bias.copy_(t[f"{prefix}{name}.bias"])
    return m


obs = t["in.obs"].reshape(T, B, -1)
act = t["in.act"].reshape(T, B, -1)
eps = t["in.eps"].reshape(T, B, -1)
y = t["in.y"].reshape(T, B)

# Actor
fc, ls = linear("actor.", "fc.0"), lstm("actor.", 7, 4)
mu_l, std_l = linear("actor.", "mean"), linear("actor.", "std")
z, _ = ls(F.relu(fc(obs)))
mu, std = mu_l(z), F.softplus(std_l(z)) + 1e-5
u = mu + std * eps
a = torch.tanh(u)
logp = (-0.5 * eps.pow(2) - std.log() - 0.5 * math.log(2 * math.pi)).sum(-1)
logp = logp - (2 * (math.log(2) - u - F.softplus(-2 * u))).sum(-1)
loss_a = (logp - a.sum(-1)).mean()
loss_a.backward()

# Critic
ofc, afc = linear("critic.", "obs_fc.0"), linear("critic.", "act_fc.0")
cl, ql = lstm("critic.", 11, 4), linear("critic.", "q")
zc, _ = cl(torch.cat([F.relu(ofc(obs)), F.relu(afc(act))], -1))
q = ql(zc).squeeze(-1)
loss_c = F.mse_loss(q, y)
loss_c.backward()

worst = 0.0


def cmp(name, ours, ref):
    global worst
    err = (ours.reshape(-1) - ref.detach().reshape(-1)).abs().max().item()
    worst = max(worst, err)
    print(f"{name:32} max |esrl - torch| = {err:.2e}")


cmp("mean", t["out.mean"], mu)
cmp("std", t["out.std"], std)
cmp("action", t["out.action"], a)
cmp("log_prob", t["out.logp"], logp)
cmp("q", t["out.q"], q)
for prefix, mods in (("actor.", {"fc.0": fc, "mean": mu_l, "std": std_l}),
                     ("critic.", {"obs_fc.0": ofc, "act_fc.0": afc, "q": ql})):
    for n, m in mods.items():
        cmp(f"grad {prefix}{n}.weight", t[f"grad.{prefix}{n}.weight"], m.weight.grad)
        cmp(f"grad {prefix}{n}.bias", t[f"grad.{prefix}{n}.bias"], m.bias.grad)
    m = ls if prefix == "actor." else cl
    cmp(f"grad {prefix}lstm.weight_ih", t[f"grad.{prefix}lstm.weight_ih"], m.weight_ih_l0.grad)
    cmp(f"grad {prefix}lstm.weight_hh", t[f"grad.{prefix}lstm.weight_hh"], m.weight_hh_l0.grad)
    cmp(f"grad {prefix}lstm.bias", t[f"grad.{prefix}lstm.bias"], m.bias_ih_l0.grad)


def rust(name, v):
    vals = ", ".join(f"{x:.9e}" for x in v.detach().reshape(-1).tolist())
    print(f"const {name}: &[f64] = &[{vals}];")


print("\n// PyTorch (f64) values for tests/torch_parity.rs")
rust("TORCH_LOG_PROB", logp.reshape(-1))
rust("TORCH_Q", q.reshape(-1))
rust("TORCH_GRAD_ACTOR_LSTM_BIAS", ls.bias_ih_l0.grad)
rust("TORCH_GRAD_CRITIC_LSTM_WEIGHT_HH", cl.weight_hh_l0.grad)
rust("TORCH_GRAD_CRITIC_ACT_FC_WEIGHT", afc.weight.grad)
print(f"\nworst {worst:.2e}")
sys.exit(0 if worst < 1e-4 else 1)
