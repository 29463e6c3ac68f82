#!/usr/bin/python3
"""The PyTorch code people would otherwise write, timed on the same work as bench_kernels.cpp.

Prints one JSON object: {case: {"ms": median step time, "gflops": ..., "steps_per_s": ...,
"cpu_percent": CPU time over wall time, "matmul_gflops": a plain product of its largest layer,
"suspect": ...}, "baseline": what it ran on}.
FLOPs are counted as in the C++ benchmark: 2·in·out per layer per sample forward, ×3 with backward.

It runs at its own best: every thread pool PyTorch can start (OpenMP, OpenBLAS, MKL, BLIS, its
intra- and inter-op pools) is pinned to --threads before torch is imported, and a --threads 1 case
that used more than 105 % of a core is refused (exit 2), not reported. --config picks one way a
PyTorch user may run it (default: the environment as it is; no-coretype: without
OPENBLAS_CORETYPE; flush-denormal: torch.set_flush_denormal(True); no-mkldnn: oneDNN off);
--best-of-configs runs each in its own process and keeps each case's fastest, naming its config.
A case whose step runs below 20 % of the rate of a plain matrix product of its largest layer is
marked suspect (its ratio against ours is not a fair one). Cases come in the forms people write:
the plain one (a triplet's or a pair's members in separate forward passes, a loop over a cell's
networks), `_stacked` (the members in one pass) and `_batched` (a cell's networks as one batched
product per layer); a comparison takes the fastest form.
Usage: /usr/bin/python3 bench/torch_reference.py [--repeats 5] [--threads 1] [--runs] [--cases a,b]
                                                 [--config NAME | --best-of-configs]
"""
import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
import time

CONFIGS = ("default", "no-coretype", "flush-denormal", "no-mkldnn")
POOLS = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "BLIS_NUM_THREADS")
SUSPECT_SHARE = 0.2


def _option(name, default):
    for i, a in enumerate(sys.argv):
        if a == name and i + 1 < len(sys.argv):
            return sys.argv[i + 1]
        if a.startswith(name + "="):
            return a.split("=", 1)[1]
    return default


# Before torch loads its BLAS: a pool sized later is too late (OpenBLAS's pthread build starts its
# own threads at load, whatever torch.set_num_threads says).
for _v in POOLS:
    os.environ[_v] = _option("--threads", "1")
if _option("--config", "default") == "no-coretype":
    os.environ.pop("OPENBLAS_CORETYPE", None)

import torch  # noqa: E402


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


def triplet_embeddings(net, x, t, stacked):
    """The three embeddings of a batch of triplets t [B, 3]: three forward passes, as people first
    write it, or (stacked) one pass over the 3B rows, as a PyTorch user who cares writes it: one
    product of 3B rows per layer instead of three of B, and no gradients accumulated across
    passes (each a full read-modify-write of every weight gradient)."""
    if stacked:
        return net(x[t.reshape(-1)]).view(t.shape[0], 3, -1).unbind(1)
    return net(x[t[:, 0]]), net(x[t[:, 1]]), net(x[t[:, 2]])


def pair_rewards(net, inputs, pair, stacked):
    """The rewards of both members of each pair [b, 2]: two passes, or (stacked) one."""
    if stacked:
        r = net(inputs[pair.reshape(-1)]).view(-1, 2)
        return r[:, 0], r[:, 1]
    return net(inputs[pair[:, 0]]).squeeze(1), net(inputs[pair[:, 1]]).squeeze(1)


def sirl_step_case(widths, B=64, T=1000, stacked=False):
    net = mlp(widths)
    x = torch.randn(T, widths[0])
    trip = torch.randint(0, T, (B, 3))
    opt = torch.optim.Adam(net.parameters(), lr=0.004)
    sched = torch.optim.lr_scheduler.ExponentialLR(opt, gamma=0.99999)

    def step():
        e1, e2, en = triplet_embeddings(net, x, trip, stacked)
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


def sirl_run_case(widths, N, epochs, T, B=64, stacked=False):
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
                e1, e2, en = triplet_embeddings(net, x, trip[perm[i:i + B]], stacked)
                d12 = ((e1 - e2) ** 2).sum(1)
                loss = (torch.relu(d12 - ((e1 - en) ** 2).sum(1) + 1)
                        + torch.relu(d12 - ((e2 - en) ** 2).sum(1) + 1)).mean()
                opt.zero_grad()
                loss.backward()
                opt.step()
                sched.step()
    return run, flops(widths, 3 * N * epochs)


def tpa_cell_case(phi_widths, hidden, epochs, T, M=100, R=20, B=64, l2=10.0, frozen=True,
                  stacked=False):
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
                    ra, rb = pair_rewards(net, inputs, pairs[r, idx], stacked)
                    loss = (torch.nn.functional.binary_cross_entropy_with_logits(ra - rb, labels[r, idx])
                            + l2 * (ra ** 2 + rb ** 2).mean())
                    opt.zero_grad()
                    loss.backward()
                    opt.step()
    return run, flops(widths, 2 * M * epochs) * R


def cpu_seconds():
    u = resource.getrusage(resource.RUSAGE_SELF)
    return u.ru_utime + u.ru_stime


# The largest layer of each case, as (rows of one product, inputs, outputs): the sanity floor's
# plain matrix product.
LARGEST = {"sirl_step_grid": (192, 128, 128), "sirl_step_jaco": (192, 2037, 1024),
           "tpa_heads_grid": (128, 128, 128), "tpa_heads_grid_batched": (128, 128, 128),
           "tpa_heads_jaco": (128, 1024, 1024), "tpa_heads_jaco_batched": (128, 1024, 1024),
           "tpa_unfrozen_jaco": (128, 2037, 1024), "tpa_unfrozen_jaco_batched": (128, 2037, 1024),
           "sirl_run_grid": (192, 128, 128), "sirl_run_jaco": (192, 2037, 1024),
           "tpa_cell_grid": (128, 128, 128), "tpa_cell_jaco": (128, 1024, 1024),
           "tpa_small_cell_jaco_frozen": (20, 1024, 1024),
           "tpa_small_cell_jaco_unfrozen": (20, 2037, 1024),
           "tpa_quick_cell_jaco_frozen": (128, 1024, 1024),
           "tpa_quick_cell_jaco_unfrozen": (128, 2037, 1024)}


def matmul_gflops(rows, n_in, n_out, min_time=0.2):
    a, b = torch.randn(rows, n_in), torch.randn(n_in, n_out)
    with torch.no_grad():
        s = time_case(lambda: torch.mm(a, b), min_time, 3)
    return 2 * rows * n_in * n_out / s * 1e-9


def baseline_config(config, threads):
    """What the baseline ran on, for the benchmark output."""
    show = torch.__config__.show()
    pick = [ln.strip() for ln in show.splitlines() if "CPU capability" in ln]
    blas = [w for w in show.replace(",", " ").split() if w.startswith(("BLAS_INFO=", "LAPACK_INFO="))]
    try:  # the BLAS Debian's alternatives resolved to (torch says only "generic")
        with open("/proc/self/maps") as f:
            libs = sorted({ln.split()[-1] for ln in f if "blas" in ln.lower() and "/" in ln})
    except OSError:
        libs = []
    return {"torch": torch.__version__, "config": config, "threads": threads, "blas_libraries": libs,
            "intra_op_threads": torch.get_num_threads(),
            "inter_op_threads": torch.get_num_interop_threads(),
            "cpu_capability": pick[0] if pick else "?", "blas": " ".join(blas),
            "mkldnn": bool(torch.backends.mkldnn.enabled),
            "env": {k: os.environ.get(k, "") for k in POOLS + ("OPENBLAS_CORETYPE", "OPENBLAS_L2_SIZE")}}


def best_of_configs(argv):
    """Runs this script once per configuration and keeps each case's fastest."""
    best, configs = {}, {}
    for c in CONFIGS:
        p = subprocess.run([sys.executable, os.path.abspath(__file__), *argv, "--config", c],
                           capture_output=True, text=True)
        if p.returncode != 0:
            sys.exit(f"torch_reference: --config {c} failed: {p.stderr.strip()[-500:]}")
        out = json.loads(p.stdout)
        configs[c] = out.pop("baseline")
        for name, v in out.items():
            if isinstance(v, dict) and (name not in best or v["ms"] < best[name]["ms"]):
                best[name] = dict(v, config=c)
    best["baseline"] = {"best_of": configs}
    return best


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
    ap.add_argument("--config", choices=CONFIGS, default="default",
                    help="how the baseline runs (read before torch is imported)")
    ap.add_argument("--best-of-configs", action="store_true",
                    help="run every --config, keep each case's fastest")
    args = ap.parse_args()
    if args.best_of_configs:
        argv = [a for a in sys.argv[1:] if a != "--best-of-configs"]
        print(json.dumps(best_of_configs(argv)))
        return
    torch.set_num_threads(args.threads)
    try:
        torch.set_num_interop_threads(1)
    except RuntimeError:
        pass  # already started: it was 1 unless the environment said otherwise
    if args.config == "flush-denormal":
        torch.set_flush_denormal(True)
    if args.config == "no-mkldnn":
        torch.backends.mkldnn.enabled = False
    # Each case is built only when it is timed (after a fresh torch.manual_seed(0)), so a run of a
    # few --cases neither builds nor holds the others' networks (the 20 Jaco copies of φ alone are
    # ~340 MB), and a case's weights do not depend on which other cases run.
    cases = {
        "sirl_step_grid": lambda: sirl_step_case([19, 128, 128, 6]),
        "sirl_step_jaco": lambda: sirl_step_case([2037, 1024, 1024, 6]),
        "sirl_step_grid_stacked": lambda: sirl_step_case([19, 128, 128, 6], stacked=True),
        "sirl_step_jaco_stacked": lambda: sirl_step_case([2037, 1024, 1024, 6], stacked=True),
        "tpa_heads_grid": lambda: tpa_heads_case(128),
        "tpa_heads_grid_batched": lambda: tpa_heads_batched_case(128),
        "tpa_heads_jaco": lambda: tpa_heads_case(1024),
        "tpa_heads_jaco_batched": lambda: tpa_heads_batched_case(1024),
        "tpa_unfrozen_jaco": lambda: tpa_unfrozen_case(2037, 1024),
        "tpa_unfrozen_jaco_batched": lambda: tpa_unfrozen_batched_case(2037, 1024),
    }
    runs = {}  # whole units, timed end to end: the same units as bench_pipeline.cpp
    if args.runs or args.cases:
        runs = {
            "sirl_run_grid": lambda: sirl_run_case([19, 128, 128, 6], N=1000, epochs=10, T=1960),
            "sirl_run_jaco": lambda: sirl_run_case([2037, 1024, 1024, 6], N=200, epochs=2, T=2000),
            "tpa_cell_grid": lambda: tpa_cell_case([19, 128, 128, 6], 128, epochs=20, T=1960),
            "tpa_cell_jaco": lambda: tpa_cell_case([2037, 1024, 1024, 6], 1024, epochs=2, T=2000,
                                                   l2=1.0),
            # quick's smallest JacoRobot cells (BM_TpaSmallCell): M = 10, 15 epochs
            "tpa_small_cell_jaco_frozen": lambda: tpa_cell_case(
                [2037, 1024, 1024, 6], 1024, epochs=15, T=2000, M=10, l2=1.0),
            "tpa_small_cell_jaco_unfrozen": lambda: tpa_cell_case(
                [2037, 1024, 1024, 6], 1024, epochs=15, T=2000, M=10, l2=1.0, frozen=False),
            # quick's largest JacoRobot cells (BM_TpaQuickCell): M = 100, 15 epochs
            "tpa_quick_cell_jaco_frozen": lambda: tpa_cell_case(
                [2037, 1024, 1024, 6], 1024, epochs=15, T=2000, M=100, l2=1.0),
            "tpa_quick_cell_jaco_unfrozen": lambda: tpa_cell_case(
                [2037, 1024, 1024, 6], 1024, epochs=15, T=2000, M=100, l2=1.0, frozen=False),
        }
        # Each unit again as a PyTorch user who cares writes it: a triplet's or a pair's members
        # in one forward pass (triplet_embeddings, pair_rewards).
        stacked = {
            "sirl_run_grid": (sirl_run_case, ([19, 128, 128, 6],), dict(N=1000, epochs=10, T=1960)),
            "sirl_run_jaco": (sirl_run_case, ([2037, 1024, 1024, 6],), dict(N=200, epochs=2, T=2000)),
            "tpa_cell_grid": (tpa_cell_case, ([19, 128, 128, 6], 128), dict(epochs=20, T=1960)),
            "tpa_cell_jaco": (tpa_cell_case, ([2037, 1024, 1024, 6], 1024),
                              dict(epochs=2, T=2000, l2=1.0)),
            "tpa_small_cell_jaco_frozen": (tpa_cell_case, ([2037, 1024, 1024, 6], 1024),
                                           dict(epochs=15, T=2000, M=10, l2=1.0)),
            "tpa_small_cell_jaco_unfrozen": (tpa_cell_case, ([2037, 1024, 1024, 6], 1024),
                                             dict(epochs=15, T=2000, M=10, l2=1.0, frozen=False)),
            "tpa_quick_cell_jaco_frozen": (tpa_cell_case, ([2037, 1024, 1024, 6], 1024),
                                           dict(epochs=15, T=2000, M=100, l2=1.0)),
            "tpa_quick_cell_jaco_unfrozen": (tpa_cell_case, ([2037, 1024, 1024, 6], 1024),
                                             dict(epochs=15, T=2000, M=100, l2=1.0, frozen=False)),
        }
        for name, (make, a, kw) in stacked.items():
            runs[name + "_stacked"] = lambda make=make, a=a, kw=kw: make(*a, **kw, stacked=True)
        cases.update(runs)
    if args.cases:
        wanted = args.cases.split(",")
        unknown = [c for c in wanted if c not in cases]
        if unknown:
            sys.exit(f"torch_reference: no case {', '.join(unknown)}; cases: {', '.join(cases)}")
        cases = {c: cases[c] for c in wanted}
    out = {"torch": torch.__version__, "threads": args.threads,
           "baseline": baseline_config(args.config, args.threads)}
    refused = []
    for name, build in cases.items():
        torch.manual_seed(0)
        step, fl = build()
        c0, w0 = cpu_seconds(), time.perf_counter()
        s = time_run(step, args.repeats) if name in runs else time_case(step, args.min_time, args.repeats)
        cpu = 100 * (cpu_seconds() - c0) / (time.perf_counter() - w0)
        base = name.removesuffix("_stacked").removesuffix("_batched")
        mm = matmul_gflops(*LARGEST[base]) if base in LARGEST else 0.0
        g = fl / s * 1e-9
        out[name] = {"ms": s * 1e3, "gflops": g, "steps_per_s": 1 / s, "cpu_percent": cpu,
                     "matmul_gflops": mm, "suspect": bool(mm and g < SUSPECT_SHARE * mm)}
        if args.threads == 1 and cpu > 105:
            refused.append(f"{name} ({cpu:.0f} % CPU)")
    if refused:
        sys.exit("torch_reference: with --threads 1 these cases used more than one core, a thread "
                 "pool was not pinned: " + ", ".join(refused))
    print(json.dumps(out))


if __name__ == "__main__":
    main()
