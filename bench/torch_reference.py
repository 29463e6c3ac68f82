#!/usr/bin/python3
"""The PyTorch code people would otherwise write, timed on the same work as bench_kernels.cpp.

Prints one JSON object: {case: {"ms": median step time, "gflops": ..., "steps_per_s": ...}}.
FLOPs are counted as in the C++ benchmark: 2·in·out per layer per sample forward, ×3 with backward.
Usage: /usr/bin/python3 bench/torch_reference.py [--repeats 5] [--threads 1] [--runs] [--cases a,b]
"""
import argparse
import json
import statistics
import sys
import time

import torch


def mlp(widths, linear=()):
    """Linear layers with a ReLU after every one but the last and those listed in `linear`."""
    layers = []
    for i in range(len(widths) - 1):
        layers.append(torch.nn.Linear(widths[i], widths[i + 1]))
        if i + 2 < len(widths) and i not in linear:
            layers.append(torch.nn.ReLU())
    return torch.nn.Sequential(*layers)


def flops(widths, samples):
    return 3 * samples * sum(2 * widths[i] * widths[i + 1] for i in range(len(widths) - 1))


def sirl_step_case(widths, B=64, T=1000):
    net = mlp(widths)
    x = torch.randn(T, widths[0])
    trip = torch.randint(0, T, (B, 3))
    opt = torch.optim.Adam(net.parameters(), lr=0.004)
    sched = torch.optim.lr_scheduler.ExponentialLR(opt, gamma=0.99999)

    def step():
        e1, e2, en = net(x[trip[:, 0]]), net(x[trip[:, 1]]), net(x[trip[:, 2]])
        d12 = ((e1 - e2) ** 2).sum(1)
        loss = (torch.relu(d12 - ((e1 - en) ** 2).sum(1) + 1) + torch.relu(d12 - ((e2 - en) ** 2).sum(1) + 1)).mean()
        opt.zero_grad()
        loss.backward()
        opt.step()
        sched.step()
    return step, flops(widths, 3 * B)


def tpa_heads_case(hidden, M=20, B=64, T=1000):
    widths = [6, hidden, hidden, 1]
    heads = [mlp(widths) for _ in range(M)]
    x = torch.randn(T, 6)
    pairs = torch.randint(0, T, (M, B, 2))
    labels = torch.randint(0, 2, (M, B)).float()
    opt = torch.optim.Adam([p for h in heads for p in h.parameters()], lr=0.001)

    def step():
        total = 0
        for m, h in enumerate(heads):
            ra, rb = h(x[pairs[m, :, 0]]).squeeze(1), h(x[pairs[m, :, 1]]).squeeze(1)
            logits = ra - rb
            loss = torch.nn.functional.binary_cross_entropy_with_logits(logits, labels[m])
            total = total + loss + 10 * (ra ** 2 + rb ** 2).mean()
        opt.zero_grad()
        total.backward()
        opt.step()
    return step, flops(widths, 2 * B) * M


def tpa_heads_batched_case(hidden, M=20, B=64, T=1000):
    """The 20 heads as a PyTorch user who cares writes them: weights stacked per layer, one
    batched product (torch.baddbmm) per layer for all heads, both trajectories of a pair in one pass."""
    widths = [6, hidden, hidden, 1]
    params = []
    for i in range(3):
        bound = 1 / widths[i] ** 0.5  # as nn.Linear initialises
        params.append(torch.nn.Parameter(torch.empty(M, widths[i], widths[i + 1]).uniform_(-bound, bound)))
        params.append(torch.nn.Parameter(torch.empty(M, 1, widths[i + 1]).uniform_(-bound, bound)))
    x = torch.randn(T, 6)
    pairs = torch.randint(0, T, (M, B, 2))
    labels = torch.randint(0, 2, (M, B)).float()
    opt = torch.optim.Adam(params, lr=0.001)

    def step():
        h = torch.cat([x[pairs[:, :, 0]], x[pairs[:, :, 1]]], dim=1)  # [M, 2B, 6]
        for i in range(3):
            h = torch.baddbmm(params[2 * i + 1], h, params[2 * i])
            if i < 2:
                h = torch.relu(h)
        ra, rb = h[:, :B, 0], h[:, B:, 0]
        bce = torch.nn.functional.binary_cross_entropy_with_logits(ra - rb, labels, reduction="none")
        total = bce.mean(1).sum() + 10 * (ra ** 2 + rb ** 2).mean(1).sum()
        opt.zero_grad()
        total.backward()
        opt.step()
    return step, flops(widths, 2 * B) * M


# An unfrozen TPA cell: φ (in→h→h→6, linear output) fine-tuned with a head (6→h→h→1) per reward.
def unfrozen_widths(phi_in, hidden):
    return [phi_in, hidden, hidden, 6, hidden, hidden, 1], (2,)


def tpa_unfrozen_case(phi_in, hidden, M=20, B=32, T=400):
    """20 copies of φ + head as people write it: one network per reward, a loop, one Adam."""
    widths, linear = unfrozen_widths(phi_in, hidden)
    nets = [mlp(widths, linear) for _ in range(M)]
    x = torch.randn(T, phi_in)
    pairs = torch.randint(0, T, (M, B, 2))
    labels = torch.randint(0, 2, (M, B)).float()
    opt = torch.optim.Adam([p for n in nets for p in n.parameters()], lr=0.001)

    def step():
        total = 0
        for m, n in enumerate(nets):
            r = n(torch.cat([x[pairs[m, :, 0]], x[pairs[m, :, 1]]])).squeeze(1)
            ra, rb = r[:B], r[B:]
            loss = torch.nn.functional.binary_cross_entropy_with_logits(ra - rb, labels[m])
            total = total + loss + 10 * (ra ** 2 + rb ** 2).mean()
        opt.zero_grad()
        total.backward()
        opt.step()
    return step, flops(widths, 2 * B) * M


def tpa_unfrozen_batched_case(phi_in, hidden, M=20, B=32, T=400):
    """The same cell batched: each layer's 20 weight matrices stacked, one torch.baddbmm."""
    widths, linear = unfrozen_widths(phi_in, hidden)
    params = []
    for i in range(len(widths) - 1):
        bound = 1 / widths[i] ** 0.5
        params.append(torch.nn.Parameter(torch.empty(M, widths[i], widths[i + 1]).uniform_(-bound, bound)))
        params.append(torch.nn.Parameter(torch.empty(M, 1, widths[i + 1]).uniform_(-bound, bound)))
    x = torch.randn(T, phi_in)
    pairs = torch.randint(0, T, (M, B, 2))
    labels = torch.randint(0, 2, (M, B)).float()
    opt = torch.optim.Adam(params, lr=0.001)

    def step():
        h = torch.cat([x[pairs[:, :, 0]], x[pairs[:, :, 1]]], dim=1)  # [M, 2B, in]
        for i in range(len(widths) - 1):
            h = torch.baddbmm(params[2 * i + 1], h, params[2 * i])
            if i + 2 < len(widths) and i not in linear:
                h = torch.relu(h)
        ra, rb = h[:, :B, 0], h[:, B:, 0]
        bce = torch.nn.functional.binary_cross_entropy_with_logits(ra - rb, labels, reduction="none")
        total = bce.mean(1).sum() + 10 * (ra ** 2 + rb ** 2).mean(1).sum()
        opt.zero_grad()
        total.backward()
        opt.step()
    return step, flops(widths, 2 * B) * M


def sirl_run_case(widths, N, epochs, T, B=64):
    """A whole SIRL training run as people write it: shuffled mini-batches, Adam + ExponentialLR."""
    x = torch.randn(T, widths[0])
    trip = torch.randint(0, T, (N, 3))

    def run():
        net = mlp(widths)
        opt = torch.optim.Adam(net.parameters(), lr=0.004)
        sched = torch.optim.lr_scheduler.ExponentialLR(opt, gamma=0.99999)
        for _ in range(epochs):
            perm = torch.randperm(N)
            for i in range(0, N, B):
                t = trip[perm[i:i + B]]
                e1, e2, en = net(x[t[:, 0]]), net(x[t[:, 1]]), net(x[t[:, 2]])
                d12 = ((e1 - e2) ** 2).sum(1)
                loss = (torch.relu(d12 - ((e1 - en) ** 2).sum(1) + 1)
                        + torch.relu(d12 - ((e2 - en) ** 2).sum(1) + 1)).mean()
                opt.zero_grad()
                loss.backward()
                opt.step()
                sched.step()
    return run, flops(widths, 3 * N * epochs)


def tpa_cell_case(phi_widths, hidden, epochs, T, M=100, R=20, B=64, l2=10.0, frozen=True):
    """One TPA cell as people write it: for each of R test rewards its own network and optimizer,
    trained on M pairs, shuffled mini-batches. Frozen: φ's embeddings computed once under no_grad,
    and a head on them; unfrozen: each reward fine-tunes its own copy of φ with its head (φ's
    output layer stays linear), on the raw inputs."""
    x = torch.randn(T, phi_widths[0])
    phi = mlp(phi_widths)
    pairs = torch.randint(0, T, (R, M, 2))
    labels = torch.randint(0, 2, (R, M)).float()
    head_widths = [phi_widths[-1], hidden, hidden, 1]
    widths = head_widths if frozen else phi_widths + head_widths[1:]

    def run():
        if frozen:
            with torch.no_grad():
                inputs = phi(x)
        else:
            inputs = x
        for r in range(R):
            net = mlp(widths, () if frozen else (len(phi_widths) - 2,))
            if not frozen:  # φ's layers first, from φ's weights
                with torch.no_grad():
                    for dst, src in zip(net, phi):
                        if isinstance(src, torch.nn.Linear):
                            dst.weight.copy_(src.weight)
                            dst.bias.copy_(src.bias)
            opt = torch.optim.Adam(net.parameters(), lr=0.001)
            for _ in range(epochs):
                perm = torch.randperm(M)
                for i in range(0, M, B):
                    idx = perm[i:i + B]
                    ra = net(inputs[pairs[r, idx, 0]]).squeeze(1)
                    rb = net(inputs[pairs[r, idx, 1]]).squeeze(1)
                    loss = (torch.nn.functional.binary_cross_entropy_with_logits(ra - rb, labels[r, idx])
                            + l2 * (ra ** 2 + rb ** 2).mean())
                    opt.zero_grad()
                    loss.backward()
                    opt.step()
    return run, flops(widths, 2 * M * epochs) * R


def time_case(step, min_time=1.0, repeats=5):
    for _ in range(3):
        step()
    samples = []
    for _ in range(repeats):
        n, t0 = 0, time.perf_counter()
        while time.perf_counter() - t0 < min_time / repeats:
            step()
            n += 1
        samples.append((time.perf_counter() - t0) / n)
    return statistics.median(samples)


def time_run(run, repeats):
    run()  # warm-up
    return statistics.median(_timed(run) for _ in range(repeats))


def _timed(f):
    t0 = time.perf_counter()
    f()
    return time.perf_counter() - t0


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--min-time", type=float, default=2.0, help="seconds per case")
    ap.add_argument("--runs", action="store_true", help="also time whole training runs and TPA cells")
    ap.add_argument("--cases", help="comma-separated case names: time only these (runs included)")
    args = ap.parse_args()
    torch.set_num_threads(args.threads)
    torch.manual_seed(0)
    cases = {
        "sirl_step_grid": sirl_step_case([19, 128, 128, 6]),
        "sirl_step_jaco": sirl_step_case([2037, 1024, 1024, 6]),
        "tpa_heads_grid": tpa_heads_case(128),
        "tpa_heads_grid_batched": tpa_heads_batched_case(128),
        "tpa_heads_jaco": tpa_heads_case(1024),
        "tpa_heads_jaco_batched": tpa_heads_batched_case(1024),
        "tpa_unfrozen_jaco": tpa_unfrozen_case(2037, 1024),
        "tpa_unfrozen_jaco_batched": tpa_unfrozen_batched_case(2037, 1024),
    }
    runs = {}  # whole units, timed end to end: the same units as bench_pipeline.cpp
    if args.runs or args.cases:
        runs = {
            "sirl_run_grid": sirl_run_case([19, 128, 128, 6], N=1000, epochs=10, T=1960),
            "sirl_run_jaco": sirl_run_case([2037, 1024, 1024, 6], N=200, epochs=2, T=2000),
            "tpa_cell_grid": tpa_cell_case([19, 128, 128, 6], 128, epochs=20, T=1960),
            "tpa_cell_jaco": tpa_cell_case([2037, 1024, 1024, 6], 1024, epochs=2, T=2000, l2=1.0),
            # quick's smallest JacoRobot cells (BM_TpaSmallCell): M = 10, 15 epochs
            "tpa_small_cell_jaco_frozen": tpa_cell_case([2037, 1024, 1024, 6], 1024, epochs=15,
                                                        T=2000, M=10, l2=1.0),
            "tpa_small_cell_jaco_unfrozen": tpa_cell_case([2037, 1024, 1024, 6], 1024, epochs=15,
                                                          T=2000, M=10, l2=1.0, frozen=False),
            # quick's largest JacoRobot cells (BM_TpaQuickCell): M = 100, 15 epochs
            "tpa_quick_cell_jaco_frozen": tpa_cell_case([2037, 1024, 1024, 6], 1024, epochs=15,
                                                        T=2000, M=100, l2=1.0),
            "tpa_quick_cell_jaco_unfrozen": tpa_cell_case([2037, 1024, 1024, 6], 1024, epochs=15,
                                                          T=2000, M=100, l2=1.0, frozen=False),
        }
        cases.update(runs)
    if args.cases:
        wanted = args.cases.split(",")
        unknown = [c for c in wanted if c not in cases]
        if unknown:
            sys.exit(f"torch_reference: no case {', '.join(unknown)}; cases: {', '.join(cases)}")
        cases = {c: cases[c] for c in wanted}
    out = {"torch": torch.__version__, "threads": args.threads}
    for name, (step, fl) in cases.items():
        s = time_run(step, args.repeats) if name in runs else time_case(step, args.min_time, args.repeats)
        out[name] = {"ms": s * 1e3, "gflops": fl / s * 1e-9, "steps_per_s": 1 / s}
    print(json.dumps(out))


if __name__ == "__main__":
    main()
