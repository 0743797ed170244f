#!/usr/bin/env python3
"""Fits the scripted operators' skill profiles to the paper's participants (README, "Calibration").

Runs `telegrasp-eval protocol --in-process` (simulated time: the same times as the DDS protocol)
on the FIT seeds for each candidate, and scores it:

    J = 20 * sum_g (mean_g / paper_g - 1)^2  -  (rho_E + rho_I + rho_all) / 3  +  held penalty

mean_g: the group's mean time to grasp over grasped trials (all fit seeds pooled); paper_g: the
paper's (1.30 s, 1.66 s); rho: Spearman of the per-object mean times (all fit seeds pooled) against
the paper's, per group and both groups pooled; held penalty: 1 per grasp held fewer than
--min-held (per seed, summed over groups). The paper's per-object times enter only through rho:
the per-object differences come from the operator model (object size, practice, pose error).

Search: for each point of a small grid over the shape parameters (size_standoff, aperture_time,
the learning_gain of each group), the groups' Fitts slopes are solved for the paper's means by
the secant method (the mean is nearly linear in the slope), then the grid point with the lowest J
wins. The winner is then run on the CONFIRM seeds, which the fit never saw, and both are printed.
Every run is logged as a JSON line to --log. A grid of one point re-solves the slopes only (the
final stage of the calibration, on more seeds).
"""
import argparse
import itertools
import json
import os
import subprocess
import sys
import tempfile

PAPER = {"experienced": 1.30, "inexperienced": 1.66}

# Fixed by assumption, not fitted (README, "Calibration"): human-typical values.
FIXED = {
    "experienced": dict(reaction_time=0.22, squeeze_time=0.30, fitts_intercept=0.05, transport_tolerance=0.05,
                        approach_tolerance=0.02, approach_clearance=0.05, learning_exponent=0.5,
                        correction_tolerance=0.004, thin_tolerance_fraction=0.1),
    "inexperienced": dict(reaction_time=0.28, squeeze_time=0.40, fitts_intercept=0.05, transport_tolerance=0.05,
                          approach_tolerance=0.02, approach_clearance=0.05, learning_exponent=0.5,
                          correction_tolerance=0.004, thin_tolerance_fraction=0.1),
}


def skills_text(theta):
    lines = []
    for g in ("experienced", "inexperienced"):
        lines.append(f"[{g}]")
        values = dict(FIXED[g])
        values.update(fitts_slope=theta[f"b_{g}"], learning_gain=theta[f"g_{g}"], size_standoff=theta["size"],
                      aperture_time=theta["aperture"])
        lines += [f"{k} = {v:.6g}" for k, v in values.items()]
    return "\n".join(lines) + "\n"


def ranks(x):
    order = sorted(range(len(x)), key=lambda i: x[i])
    r = [0.0] * len(x)
    i = 0
    while i < len(order):
        j = i
        while j + 1 < len(order) and x[order[j + 1]] == x[order[i]]:
            j += 1
        for k in range(i, j + 1):
            r[order[k]] = (i + j) / 2 + 1
        i = j + 1
    return r


def spearman(a, b):
    ra, rb = ranks(a), ranks(b)
    ma, mb = sum(ra) / len(ra), sum(rb) / len(rb)
    num = sum((x - ma) * (y - mb) for x, y in zip(ra, rb))
    den = (sum((x - ma) ** 2 for x in ra) * sum((y - mb) ** 2 for y in rb)) ** 0.5
    return num / den if den else float("nan")


def load_paper(path):
    rows = {}
    with open(path) as f:
        next(f)
        for line in f:
            c = line.strip().split(",")
            rows[c[1].replace("072_a", "072-a")] = {"experienced": float(c[2]), "inexperienced": float(c[3])}
    return rows


class Evaluator:
    def __init__(self, args):
        self.args = args
        self.paper = load_paper(args.paper)
        self.cache = {}
        self.work = tempfile.mkdtemp(prefix="fit-skills-")

    def run(self, theta, seed):
        key = (json.dumps(theta, sort_keys=True), seed)
        if key in self.cache:
            return self.cache[key]
        skills = os.path.join(self.work, "skills.txt")
        out = os.path.join(self.work, f"run-{seed}.json")
        with open(skills, "w") as f:
            f.write(skills_text(theta))
        cmd = [self.args.eval, "protocol", "--in-process", "--mode", "precise", "--seed", str(seed), "--skills", skills,
               "--jobs", str(self.args.jobs), "--json", out]
        if self.args.objects:
            cmd += ["--objects", self.args.objects]
        subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        with open(out) as f:
            grasps = json.load(f)["grasps"]
        self.cache[key] = grasps
        return grasps

    def score(self, theta, seeds):
        grasps = [g for s in seeds for g in self.run(theta, s)]
        res = {"theta": theta, "seeds": list(seeds)}
        penalty = 0.0
        per_object_all, j = {}, 0.0
        for g in ("experienced", "inexperienced"):
            mine = [r for r in grasps if r["group"] == g]
            times = [r["time_to_grasp_s"] for r in mine if r.get("grasped")]
            held = sum(1 for r in mine if r["held_after_lift"])
            mean = sum(times) / len(times)
            per_object = {}
            for r in mine:
                if r.get("grasped"):
                    per_object.setdefault(r["object"], []).append(r["time_to_grasp_s"])
                    per_object_all.setdefault(r["object"], []).append(r["time_to_grasp_s"])
            objs = sorted(o for o in per_object if o in self.paper)
            rho = spearman([sum(per_object[o]) / len(per_object[o]) for o in objs], [self.paper[o][g] for o in objs])
            res[g] = {"mean_s": mean, "ratio": mean / PAPER[g], "held": held, "trials": len(mine), "spearman": rho}
            penalty += max(0, self.args.min_held[g] * len(seeds) - held)
            j += 20 * (mean / PAPER[g] - 1) ** 2
        objs = sorted(o for o in per_object_all if o in self.paper)
        pooled = [(4 * self.paper[o]["experienced"] + 6 * self.paper[o]["inexperienced"]) / 10 for o in objs]
        res["all"] = {"spearman": spearman([sum(per_object_all[o]) / len(per_object_all[o]) for o in objs], pooled)}
        res["J"] = j - (res["experienced"]["spearman"] + res["inexperienced"]["spearman"] + res["all"]["spearman"]) / 3 \
            + penalty
        return res


def solve_slopes(ev, theta, seeds, log):
    """Secant on each group's Fitts slope for the paper's mean (both groups from the same runs)."""
    theta = dict(theta)
    prev = None
    for _ in range(4):
        res = ev.score(theta, seeds)
        log(res)
        if all(abs(res[g]["ratio"] - 1) < 0.015 for g in PAPER):
            return theta, res
        nxt = dict(theta)
        for g in PAPER:
            b, m = theta[f"b_{g}"], res[g]["mean_s"]
            slope = 10.0  # s of mean time per s/bit of Fitts slope (about the bits of a reach): a first guess, then measured
            if prev and abs(prev[0][f"b_{g}"] - b) > 1e-6:
                slope = (prev[1][g]["mean_s"] - m) / (prev[0][f"b_{g}"] - b)
                slope = slope if slope > 1.0 else 10.0
            nxt[f"b_{g}"] = max(0.01, b + (PAPER[g] - m) / slope)
        prev = (theta, res)
        theta = nxt
    return theta, ev.score(theta, seeds)


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--eval", default="build/bin/telegrasp-eval")
    p.add_argument("--objects", default="../shared/data/ycb")
    p.add_argument("--paper", default="client_lib/tools/report/paper_results_per_object.csv")
    p.add_argument("--fit-seeds", default="1,2")
    p.add_argument("--confirm-seeds", default="3,4")
    p.add_argument("--sizes", default="0.8", help="size_standoff grid")
    p.add_argument("--apertures", default="0.6,1.0", help="aperture_time grid (both groups)")
    p.add_argument("--gains-experienced", default="0.1", help="learning_gain grid, experienced")
    p.add_argument("--gains-inexperienced", default="1.2,2.0", help="learning_gain grid, inexperienced")
    p.add_argument("--slopes-start", default="0.074,0.045", help="Fitts slopes to start from, experienced,inexperienced")
    p.add_argument("--jobs", type=int, default=2)
    p.add_argument("--log", default="fit_skill_profiles.log")
    args = p.parse_args()
    args.min_held = {"experienced": 119, "inexperienced": 177}
    fit = [int(s) for s in args.fit_seeds.split(",")]
    confirm = [int(s) for s in args.confirm_seeds.split(",")]
    ev = Evaluator(args)
    logf = open(args.log, "a")

    def log(res):
        line = json.dumps(res)
        print(line, flush=True)
        logf.write(line + "\n")
        logf.flush()

    best = None
    start = [float(x) for x in args.slopes_start.split(",")]
    theta = {"b_experienced": start[0], "b_inexperienced": start[1]}
    grid = itertools.product([float(x) for x in args.sizes.split(",")], [float(x) for x in args.apertures.split(",")],
                             [float(x) for x in args.gains_experienced.split(",")],
                             [float(x) for x in args.gains_inexperienced.split(",")])
    for size, aperture, ge, gi in grid:
        theta = dict(theta, size=size, aperture=aperture, g_experienced=ge, g_inexperienced=gi)
        theta, res = solve_slopes(ev, theta, fit, log)
        if best is None or res["J"] < best[1]["J"]:
            best = (theta, res)
    print("BEST on fit seeds:", json.dumps(best[1]))
    conf = ev.score(best[0], confirm)
    log(dict(conf, confirm=True))
    print("CONFIRM seeds:", json.dumps(conf))
    print(skills_text(best[0]))


if __name__ == "__main__":
    main()
