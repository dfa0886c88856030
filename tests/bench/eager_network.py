#!/usr/bin/env python3
"""The PointConv U-Net in plain PyTorch eager ops, checked against and timed beside the C++ network.

Reads files written by build/bin/network_export (weights, input, the C++ outputs and forward
times), rebuilds the network as torch.nn modules whose state_dict keys are the C++ module names,
checks that its output equals the C++ output, and times its forward pass (torch.no_grad(), the
file's thread count, minimum over repetitions):

  eager_network.py FILE... [--repeats R] [--threads T] [--label L] [--results OUT.jsonl]
  eager_network.py --summary OUT.jsonl   # minimum over every row of each size, with the context

The formulation is the C++ unfused reference (ConvImplementation::kUnfused): per convolution,
relative positions gathered in float64 and scaled by the level's radius, neighbour features
gathered to [M,K,C], WeightNet h on the relative positions, [M,c_mid,K] x [M,K,C] matmul, one
linear. Optional measuring tool: needs python3-torch (Debian 12: apt-get install python3-torch).
"""

import argparse
import json
import math
import resource
import sys
import time

import torch
import torch.nn.functional as F
from torch import nn

TOLERANCE = 1e-4  # max |eager - C++| / max |C++| of the network output


class PointConv(nn.Module):
    """Efficient PointConv y_0 = W_l vec(sum_k h(p_k - p_0) x_k^T) over one neighbour list."""

    def __init__(self, channels, c_mid, pos_channels, normalize, scale, hidden=8):
        super().__init__()
        self.weightnet = nn.Sequential(nn.Linear(3, hidden), nn.ReLU(), nn.Linear(hidden, hidden),
                                       nn.ReLU(), nn.Linear(hidden, c_mid))
        self.pos_embed = (nn.Sequential(nn.Linear(3, pos_channels), nn.ReLU(),
                                        nn.Linear(pos_channels, pos_channels))
                          if pos_channels > 0 else None)
        self.linear = nn.Linear((channels + pos_channels) * c_mid, channels)
        self.normalize = normalize
        self.scale = scale

    def forward(self, query, source, x, index, mask):
        m, k = index.shape
        flat = index.clamp(min=0).reshape(-1)  # masked entries (-1) read row 0, zeroed by h
        rel = ((source.index_select(0, flat).view(m, k, 3) - query.unsqueeze(1)) /
               self.scale).float()
        xk = x.index_select(0, flat).view(m, k, x.shape[1])
        if self.pos_embed is not None:
            xk = torch.cat([xk, self.pos_embed(rel)], -1)
        h = self.weightnet(rel) * mask.unsqueeze(-1).float()  # [M,K,c_mid]
        agg = torch.matmul(h.transpose(1, 2), xk)  # [M,c_mid,C]
        count = mask.sum(1).float()
        if self.normalize:
            agg = agg / count.clamp(min=1.0).view(m, 1, 1)
        y = self.linear(agg.reshape(m, -1))
        return y * (count > 0).float().unsqueeze(1)


class ConvUnit(nn.Module):
    """relu(shortcut + expand(relu(norm(conv(relu(norm(reduce(x))))))))."""

    def __init__(self, cin, cout, cfg, pos_channels, normalize, scale):
        super().__init__()
        mid = max(1, cout // cfg["bottleneck_divisor"])
        self.reduce = nn.Linear(cin, mid)
        self.reduce_norm = nn.LayerNorm(mid) if cfg["layer_norm"] else None
        self.conv = PointConv(mid, cfg["c_mid"], pos_channels, normalize, scale)
        self.conv_norm = nn.LayerNorm(mid) if cfg["layer_norm"] else None
        self.expand = nn.Linear(mid, cout)
        self.shortcut = nn.Linear(cin, cout, bias=False) if cin != cout else None

    def forward(self, x, source, query, neighbors, resample):
        index, mask = neighbors
        r = self.reduce(x)
        if self.reduce_norm is not None:
            r = self.reduce_norm(r)
        c = self.conv(query, source, F.relu(r), index, mask)
        if self.conv_norm is not None:
            c = self.conv_norm(c)
        c = self.expand(F.relu(c))
        # A resampling unit's residual is the nearest source point's features (column 0).
        s = x.index_select(0, index[:, 0].clamp(min=0)) if resample else x
        if self.shortcut is not None:
            s = self.shortcut(s)
        return F.relu(c + s)


class InteractionBlock(nn.Module):
    """Object unit (may resample), optional skip fusion, relational unit at the query level."""

    def __init__(self, cin, cout, skip, level, cfg):
        super().__init__()
        scale = cfg["radius"] * cfg["growth"] ** level
        self.object = ConvUnit(cin, cout, cfg, cfg["pos_channels"], False, scale)
        self.fuse = nn.Linear(cout + skip, cout) if skip > 0 else None
        self.relational = ConvUnit(cout, cout, cfg, 0, True, scale)

    def forward(self, x, source, query, neighbors, resample, skip=None):
        y = self.object(x, source, query["points"], neighbors, resample)
        if self.fuse is not None:
            y = F.relu(self.fuse(torch.cat([y, skip], -1)))
        return self.relational(y, query["points"], query["points"], query["relational"], False)


def channels(cfg, level):
    return int(math.floor(cfg["width"] * cfg["width_growth"] ** level + 0.5))


class UNet(nn.Module):
    def __init__(self, cfg, in_features=7, out_features=3):
        super().__init__()
        levels, c0 = cfg["levels"], channels(cfg, 0)
        self.input_mlp = nn.Sequential(nn.Linear(in_features, c0), nn.ReLU(), nn.Linear(c0, c0),
                                       nn.ReLU())
        self.stem = nn.ModuleList(
            [InteractionBlock(c0, c0, 0, 0, cfg) for _ in range(cfg["stem_blocks"])])
        self.encoder = nn.ModuleList([
            InteractionBlock(channels(cfg, l), channels(cfg, l + 1), 0, l + 1, cfg)
            for l in range(levels - 1)
        ])
        cb = channels(cfg, levels - 1)
        self.bottleneck = nn.ModuleList([
            InteractionBlock(cb, cb, 0, levels - 1, cfg) for _ in range(cfg["bottleneck_blocks"])
        ])
        self.decoder = nn.ModuleList([
            InteractionBlock(channels(cfg, l + 1), channels(cfg, l), channels(cfg, l), l, cfg)
            for l in range(levels - 2, -1, -1)
        ])
        self.head = nn.Sequential(nn.Linear(c0, c0), nn.ReLU(), nn.Linear(c0, out_features))

    def forward(self, features, lv):
        x = self.input_mlp(features)
        for block in self.stem:
            x = block(x, lv[0]["points"], lv[0], lv[0]["same"], False)
        skips = [x]
        for l, block in enumerate(self.encoder):
            x = block(x, lv[l]["points"], lv[l + 1], lv[l + 1]["down"], True)
            skips.append(x)
        for block in self.bottleneck:
            x = block(x, lv[-1]["points"], lv[-1], lv[-1]["same"], False)
        for j, block in enumerate(self.decoder):
            l = len(lv) - 2 - j
            x = block(x, lv[l + 1]["points"], lv[l], lv[l + 1]["up"], True, skips[l])
        return self.head(x)


class DynamicsModel(nn.Module):
    """Normalised [v_t; v_{t-1}; z_t] -> U-Net -> p(t+1)."""

    def __init__(self, cfg):
        super().__init__()
        self.acceleration = cfg["target"] == "acc"
        self.unet = UNet(cfg)
        for name, size in [("velocity_mean", 3), ("velocity_std", 3), ("target_mean", 3),
                           ("target_std", 3), ("z_mean", 1), ("z_std", 1)]:
            self.register_buffer(name, torch.zeros(size))

    def forward(self, inp):
        v = (inp["velocity"] - self.velocity_mean) / self.velocity_std
        v_prev = (inp["prev_velocity"] - self.velocity_mean) / self.velocity_std
        z = (inp["position"][:, 2:3].float() - self.z_mean) / self.z_std
        return self.unet(torch.cat([v, v_prev, z], 1), inp["levels"])

    def predict_positions(self, inp):
        target = self.forward(inp) * self.target_std + self.target_mean
        delta = inp["velocity"] + target if self.acceleration else target
        return inp["position"] + delta.double()


def model_input(tensors, levels):
    """The exported flat tensor dict as the nested input DynamicsModel.forward reads."""
    lv = []
    for l in range(levels):
        p = "level.%d." % l
        level = {"points": tensors[p + "points"]}
        for name in ("same", "relational", "down", "up"):
            level[name] = (tensors[p + name + ".index"], tensors[p + name + ".mask"])
        lv.append(level)
    return {
        "position": tensors["position"],
        "velocity": tensors["velocity"],
        "prev_velocity": tensors["prev_velocity"],
        "levels": lv,
    }


def difference(a, b):
    """(max |a - b|, max |a - b| / max |b|)."""
    d = (a.double() - b.double()).abs().max().item()
    return d, d / max(b.double().abs().max().item(), 1e-30)


def minor_faults():
    return resource.getrusage(resource.RUSAGE_SELF).ru_minflt


def time_runs(fn, repeats, warmup=2):
    """(minimum wall time in ms, mean minor page faults per run) over `repeats` runs."""
    for _ in range(warmup):
        fn()
    best, faults = float("inf"), 0
    for _ in range(repeats):
        f = minor_faults()
        t = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t)
        faults += minor_faults() - f
    return 1e3 * best, faults / repeats


def run_file(path, args):
    data = torch.load(path)
    if data.get("format") != "dynscope-network-export-1":
        sys.exit("eager_network: %s: not a network_export file" % path)
    cfg = json.loads(data["config"])
    if cfg["model"] != "pointconv" or cfg["input"] != "points":
        sys.exit("eager_network: %s: only the PointConv model on point input is implemented" % path)
    threads = args.threads or data["threads"]
    torch.set_num_threads(threads)

    model = DynamicsModel(cfg)
    model.load_state_dict(data["state_dict"], strict=True)  # names and shapes must all match
    model.eval()
    inp = model_input(data["input"], cfg["levels"])
    out = data["output"]
    with torch.no_grad():
        network = model(inp)
        positions = model.predict_positions(inp)
        eager_ms, eager_faults = time_runs(lambda: model.predict_positions(inp), args.repeats)

    position = inp["position"]
    row = {
        "label": args.label,
        "points": data["points"],
        "threads": threads,
        "eager_ms": eager_ms,
        "fused_ms": data["time_ms"]["fused"],
        "unfused_ms": data["time_ms"]["unfused"],
        "eager_faults": eager_faults,
        "fused_faults": data["minor_faults_per_pass"]["fused"],
        "unfused_faults": data["minor_faults_per_pass"]["unfused"],
        "cpp_repeats": data["repeats"],
        "eager_repeats": args.repeats,
        "cpp_context": data["context"],
    }
    for ref in ("unfused", "fused"):
        row["network_vs_" + ref] = difference(network, out["network." + ref])
        row["delta_vs_" + ref] = difference(positions - position,
                                            out["positions." + ref] - position)
    row["cpp_fused_vs_unfused"] = difference(out["network.fused"], out["network.unfused"])
    ok = all(row[key][1] <= TOLERANCE for key in ("network_vs_unfused", "network_vs_fused"))
    print("%-6d points  %s %8.2f ms (%.0f faults/pass) | C++ fused %.2f ms, unfused %.2f ms |"
          " eager/fused %.2fx | network output vs C++ unfused: max abs %.1e rel %.1e, vs fused:"
          " max abs %.1e rel %.1e%s" %
          (row["points"], args.label, eager_ms, eager_faults, row["fused_ms"], row["unfused_ms"],
           eager_ms / row["fused_ms"], *row["network_vs_unfused"], *row["network_vs_fused"],
           "" if ok else "  MISMATCH (tolerance %.0e)" % TOLERANCE))
    return row, ok


def mapped_blas():
    """The BLAS libraries this process has mapped (after a matrix product has loaded them)."""
    torch.mm(torch.ones(64, 64), torch.ones(64, 64))
    try:
        with open("/proc/self/maps") as maps:
            paths = {line.split()[-1] for line in maps if "blas" in line.lower()}
    except OSError:
        return "unknown"
    return ", ".join(sorted(p for p in paths if p.startswith("/"))) or "none mapped"


def print_python_context():
    print("python %s" % sys.version.split()[0])
    print("torch %s" % torch.__version__)
    print("blas %s" % mapped_blas())
    print("torch_intraop_threads %d" % torch.get_num_threads())
    print(torch.__config__.parallel_info().rstrip())
    print(torch.__config__.show().rstrip())


def summarise(path):
    rows = [json.loads(line) for line in open(path) if line.strip()]
    if not rows:
        sys.exit("eager_network: %s: no results" % path)
    print("== C++ (network_export) context")
    print(rows[0]["cpp_context"].rstrip())
    print("== Python context")
    print_python_context()
    print("== %d rows; minimum over the rounds of each column (each a minimum over its own "
          "repetitions); ratio range: per round" % len(rows))
    head = ("points", "eager side", "rounds", "eager ms", "ours fused ms", "ours unfused ms",
            "eager/fused", "per round", "unfused/fused", "faults/pass eager, fused, unfused",
            "max rel diff")
    print("| " + " | ".join(head) + " |")
    print("|" + "---|" * len(head))
    keys = sorted({(r["points"], r["label"]) for r in rows})
    for points, label in keys:
        group = [r for r in rows if r["points"] == points and r["label"] == label]
        eager = min(r["eager_ms"] for r in group)
        fused = min(r["fused_ms"] for r in group)
        unfused = min(r["unfused_ms"] for r in group)
        per_round = [r["eager_ms"] / r["fused_ms"] for r in group]
        rel = max(max(r["network_vs_unfused"][1], r["network_vs_fused"][1]) for r in group)
        faults = [sum(r[key] for r in group) / len(group)
                  for key in ("eager_faults", "fused_faults", "unfused_faults")]
        print("| %d | %s | %d | %.2f | %.2f | %.2f | **%.2fx** | %.2f-%.2fx | %.2fx | %.0f, %.0f, %.0f"
              " | %.1e |" % (points, label, len(group), eager, fused, unfused, eager / fused,
                             min(per_round), max(per_round), unfused / fused, *faults, rel))


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("files", nargs="*", help="network_export output files")
    parser.add_argument("--repeats", type=int, default=20)
    parser.add_argument("--threads", type=int, default=0, help="default: the file's")
    parser.add_argument("--label", default="eager")
    parser.add_argument("--results", help="append one JSON line per file")
    parser.add_argument("--summary", help="print the table of a --results file and exit")
    parser.add_argument("--context", action="store_true", help="print the torch context first")
    args = parser.parse_args()
    if args.summary:
        summarise(args.summary)
        return 0
    if not args.files:
        parser.error("no input files")
    if args.context:
        print_python_context()
    all_ok = True
    for path in args.files:
        row, ok = run_file(path, args)
        all_ok = all_ok and ok
        if args.results:
            with open(args.results, "a") as out:
                out.write(json.dumps(row) + "\n")
    return 0 if all_ok else 1


if __name__ == "__main__":
    sys.exit(main())
