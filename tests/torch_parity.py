#!/usr/bin/python3
"""PyTorch side of the kernel parity test (tests/test_torch_parity.cpp).

Reads the case the C++ test wrote into DIR (raw little-endian arrays + meta.txt), trains the same
MLP from the same initial weights on the same triplet sequence with the paper's symmetric
triplet loss and Adam + ExponentialLR, written as the paper's PyTorch code would be, and writes:
  torch_losses.f32            loss at every step                     [steps]
  torch_params.f32            final weights (our flat layout)        [P]
  ckpt_<s>_pre.f32 / _post.f32  (params | Adam m | Adam v) before and after step s, every
                              `every` steps: the C++ side replays single steps from them.
  torch64_params.f32          final weights of the same run in float64 (rounding sensitivity)
"""
import os
import sys

import numpy as np
import torch


def build(widths, flat, dtype):
    layers = []
    for i in range(len(widths) - 1):
        layers.append(torch.nn.Linear(widths[i], widths[i + 1]))
        if i + 2 < len(widths):
            layers.append(torch.nn.ReLU())
    net = torch.nn.Sequential(*layers).to(dtype)
    linears = [m for m in net if isinstance(m, torch.nn.Linear)]
    off = 0
    with torch.no_grad():  # our flat layout: per layer W [out, in] row-major, then b [out]
        for lin in linears:
            for p in (lin.weight, lin.bias):
                n = p.numel()
                p.copy_(flat[off:off + n].reshape(p.shape))
                off += n
    assert off == flat.numel(), "parameter count mismatch"
    return net, [p for lin in linears for p in (lin.weight, lin.bias)]


def flat_state(params, opt):
    def cat(ts):
        return torch.cat([t.detach().reshape(-1) for t in ts]).numpy().astype("<f4")
    m = [opt.state[p]["exp_avg"] if p in opt.state else torch.zeros_like(p) for p in params]
    v = [opt.state[p]["exp_avg_sq"] if p in opt.state else torch.zeros_like(p) for p in params]
    return np.concatenate([cat(params), cat(m), cat(v)])


def train(d, meta, dtype, checkpoints):
    widths = [int(w) for w in meta["widths"].split(",")]
    steps, batch, every = int(meta["steps"]), int(meta["batch"]), int(meta["every"])
    lr, decay, margin = float(meta["lr"]), float(meta["decay"]), float(meta["margin"])
    x = torch.from_numpy(np.fromfile(os.path.join(d, "x.f32"), dtype="<f4").reshape(-1, widths[0]))
    x = x.to(dtype)
    trip = torch.from_numpy(np.fromfile(os.path.join(d, "triplets.i32"), dtype="<i4").astype(np.int64))
    trip = trip.reshape(steps, batch, 3)
    flat = torch.from_numpy(np.fromfile(os.path.join(d, "init.f32"), dtype="<f4")).to(dtype)
    net, params = build(widths, flat, dtype)
    opt = torch.optim.Adam(net.parameters(), lr=lr)
    sched = torch.optim.lr_scheduler.ExponentialLR(opt, gamma=decay)
    losses = []
    for s in range(steps):
        if checkpoints and s % every == 0:
            flat_state(params, opt).tofile(os.path.join(d, f"ckpt_{s}_pre.f32"))
        t = trip[s]
        e1, e2, en = net(x[t[:, 0]]), net(x[t[:, 1]]), net(x[t[:, 2]])
        d12 = ((e1 - e2) ** 2).sum(1)
        d1n = ((e1 - en) ** 2).sum(1)
        d2n = ((e2 - en) ** 2).sum(1)
        loss = (torch.relu(d12 - d1n + margin) + torch.relu(d12 - d2n + margin)).mean()
        opt.zero_grad()
        loss.backward()
        opt.step()
        sched.step()
        losses.append(loss.item())
        if checkpoints and s % every == 0:
            flat_state(params, opt).tofile(os.path.join(d, f"ckpt_{s}_post.f32"))
    final = torch.cat([p.detach().reshape(-1) for p in params]).numpy().astype("<f4")
    return np.asarray(losses, dtype="<f4"), final


def main(d):
    meta = dict(line.split("=", 1) for line in open(os.path.join(d, "meta.txt")).read().split())
    torch.set_num_threads(1)
    losses, final = train(d, meta, torch.float32, checkpoints=True)
    losses.tofile(os.path.join(d, "torch_losses.f32"))
    final.tofile(os.path.join(d, "torch_params.f32"))
    _, final64 = train(d, meta, torch.float64, checkpoints=False)
    final64.tofile(os.path.join(d, "torch64_params.f32"))


if __name__ == "__main__":
    main(sys.argv[1])
