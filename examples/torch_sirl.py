#!/usr/bin/python3
"""Bring your own representation: SIRL written in plain PyTorch, scored by `sirl evaluate`.

The three steps a researcher with a method of their own takes (README, "Bring your own
representation"):

    sirl dataset --profile smoke --out out/smoke-train.h5          # what a method may learn from
    /usr/bin/python3 examples/torch_sirl.py out/smoke-train.h5 --out out/torch_sirl.h5
    sirl evaluate out/torch_sirl.h5 --name torch_sirl --profile smoke --figures out/smoke+torch

This file is step 2 for one method: the paper's SIRL (a φ trained on similarity triplets with the
symmetric triplet loss), written as its authors' PyTorch code would be, with PyTorch's own
initialisation, batch order and Adam. It reads the triplets and Ξ from the training file and the
hyper-parameters the engine's SIRL trains with (the file's `hyper` attribute), and writes one
embedding of Ξ per environment × seed × N that `sirl evaluate` asks for. Its FPE and TPA should
agree with the engine's SIRL within the spread over seeds: a cross-check of the protocol (not a
target to tune), since the two differ only in their random streams.
"""
import argparse
import os
import sys
import time

import numpy as np
import torch

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "python"))
import sirl_bench  # noqa: E402


def mlp(widths, relu_output):
    layers = []
    for i in range(len(widths) - 1):
        layers.append(torch.nn.Linear(widths[i], widths[i + 1]))
        if i + 2 < len(widths) or relu_output:
            layers.append(torch.nn.ReLU())
    return torch.nn.Sequential(*layers)


def symmetric_triplet_loss(e1, e2, en, margin):
    """The paper's eq. 2 on squared distances, averaged over the batch: both positives of a
    triplet should be closer to each other than either is to the negative."""
    d12 = ((e1 - e2) ** 2).sum(1)
    loss = torch.relu(d12 - ((e1 - en) ** 2).sum(1) + margin) + \
        torch.relu(d12 - ((e2 - en) ** 2).sum(1) + margin)
    return loss.mean()


def train_sirl(X, triplets, h, seed, epochs):
    """φ trained on `triplets` [N, 3] (positive 1, positive 2, negative rows of X), with the
    engine's hyper-parameters h (the file's @hyper, typed: widths a list, flags bool); returns
    φ(X)."""
    torch.manual_seed(seed)
    widths = [X.shape[1]] + h["phi.hidden"] + [h["phi.embedding_dim"]]
    phi = mlp(widths, h["phi.relu_output"])
    opt = torch.optim.Adam(phi.parameters(), lr=h["sirl.lr"])
    decay = torch.optim.lr_scheduler.ExponentialLR(opt, gamma=h["sirl.lr_decay"])
    batch, margin = h["sirl.batch"], h["sirl.margin"]
    Xt, T = torch.from_numpy(X), torch.from_numpy(triplets.astype(np.int64))
    g = torch.Generator().manual_seed(seed)
    for _ in range(epochs):
        for idx in torch.randperm(len(T), generator=g).split(batch):
            t = T[idx]
            e = phi(Xt[t.reshape(-1)]).reshape(len(t), 3, -1)
            loss = symmetric_triplet_loss(e[:, 0], e[:, 1], e[:, 2], margin)
            opt.zero_grad()
            loss.backward()
            opt.step()
            decay.step()
    with torch.no_grad():
        return phi(Xt).numpy()


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("train", help="the file `sirl dataset --profile P --out FILE` wrote")
    ap.add_argument("--out", required=True, help="embeddings file for `sirl evaluate`")
    ap.add_argument("--envs", default="",
                    help="comma-separated environments (default: every one in the file); pass "
                         "the same list to `sirl evaluate --envs`")
    ap.add_argument("--epochs", type=int, default=0,
                    help="epochs per training (default: the engine's sirl.epochs of each env)")
    ap.add_argument("--threads", type=int, default=os.cpu_count())
    a = ap.parse_args()
    torch.set_num_threads(a.threads)
    try:
        data = sirl_bench.datasets(a.train)
        # Every (env, seed, N) `sirl evaluate` asks for: the profile's seeds × evaluate_N.
        wanted = sirl_bench.embedding_keys(data, [e for e in a.envs.split(",") if e] or None)
    except sirl_bench.ResultsError as e:
        sys.exit(f"torch_sirl: {e}")
    embeddings = {}
    for env, seed, N in wanted:
        g = data[env]
        h = g["attrs"]["hyper"]  # {"phi.hidden": [128, 128], "sirl.lr": 0.004, ...}
        epochs = a.epochs or h["sirl.epochs"]
        X = np.asarray(g["inputs"], dtype=np.float32)  # read once per environment, then kept
        similarity = g["seeds"][f"s{seed}"]["queries"]["similarity"]
        t0 = time.perf_counter()
        # φ's initialisation and batch order: PyTorch's streams, from (seed, N).
        embeddings[(env, seed, N)] = train_sirl(X, similarity[:N], h, 1000 * seed + N, epochs)
        print(f"{env} seed {seed} N {N}: {epochs} epochs in {time.perf_counter() - t0:.1f} s",
              file=sys.stderr)
    sirl_bench.write_embeddings(a.out, embeddings, method="SIRL in PyTorch (examples/torch_sirl.py)")
    print(f"wrote {a.out}: {len(embeddings)} embeddings of Ξ")


if __name__ == "__main__":
    main()
