#!/usr/bin/env python3
"""Stream surfaces on the shared real data sets in three variants side by side: without the fold
guard, the stall cut and gap closing (the engine as it was before them), with the guard only, and
the default (all three): quads, angles, edge spread, folds, non-manifold edges, T-junctions, fold
rips, stall cuts, gap faces, boundary edges, why α was clamped and insertions fell back, seed
shots skipped, field evaluations, and time by stage. --baseline adds a row per case from another
build run with its defaults (an older one: figures its report lacks print as "-").

    tools/realdata_table.py [--binary build/apps/orthofront] [--baseline OLD/orthofront]
                            [--data ../shared/datasets] [--json table.json]

Data sets that are absent are skipped with a line saying so."""

import argparse
import json
import os
import subprocess
import sys
import tempfile

# (name, extra stream options)
VARIANTS = [
    ("before", "--no-fold-guard --stall-steps 0 --no-close-gaps"),
    ("guard", "--stall-steps 0 --no-close-gaps"),
    ("default", ""),
]

CASES = [
    ("tornado, seed across the core", "tornado/1.vec",
     "--seed line:10,24,24:38,24,24 --seed-count 20 --edge 0.5 --steps 300"),
    ("tornado, vertical seed", "tornado/1.vec",
     "--seed line:30,24,10:30,24,30 --seed-count 20 --edge 0.5 --steps 200"),
    ("bubble chamber", "bubble-chamber/BubbleChamber_11x11x10_T0.am",
     "--seed line:0,-0.03,0.02:0,0.03,0.02 --seed-count 20 --edge 0.004 --steps 100"),
    ("square cylinder 1608", "square-cylinder-2d/sqflow2D-1608.nrrd",
     "--seed line:-10,-3,0:-10,3,0 --seed-count 20 --edge 0.1 --steps 400"),
    ("square cylinder 1608, gaps within 4 l", "square-cylinder-2d/sqflow2D-1608.nrrd",
     "--seed line:-10,-3,0:-10,3,0 --seed-count 20 --edge 0.1 --steps 400 --gap-distance 4"),
    ("square cylinder 3928", "square-cylinder-2d/sqflow2D-3928.nrrd",
     "--seed line:-10,-3,0:-10,3,0 --seed-count 20 --edge 0.1 --steps 400"),
    ("square cylinder recirculation", "square-cylinder-2d/sqflow2D-1608.nrrd",
     "--seed line:0.8,-0.6,0:0.8,0.6,0 --seed-count 20 --edge 0.02 --steps 3000"),
]


def run(binary, field, args, variant, work):
    out = os.path.join(work, "surface.vtp")
    report = os.path.join(work, "surface.json")
    command = [binary, "stream", "--field", field, "--out", out, "--report", report, "--quiet"]
    command += args.split() + variant.split()
    env = dict(os.environ, ORTHOFRONT_HISTOGRAMS="0")
    subprocess.run(command, check=True, env=env)
    with open(report) as f:
        return json.load(f)


def row(name, variant, r):
    c, q, t = r["counts"], r["quality"], r["times_s"]
    inserted = (c["streamline_insertions"] + c.get("previous_row_insertions", 0) +
                c["insertion_fallbacks"])
    gaps = c.get("gaps_closed")
    return {
        "case": name, "variant": variant, "vertices": c["vertices"],
        "quads_pct": 100.0 * c["quads"] / max(1, c["faces"]),
        "angles_within_10_pct": 100.0 * q["quad_angles_within_10deg"],
        "edge_spread": q["edge_spread_median"], "folds": q["folds"],
        "non_manifold_edges": q["non_manifold_edges"], "t_junctions": q["t_junctions"],
        "degenerate_faces": q["degenerate_faces"], "fold_rips": c.get("fold_rips"),
        "stall_cuts": c.get("stall_cuts"), "gap_faces": gaps["faces"] if gaps else None,
        "boundary_edges": q.get("boundary_edges"),
        "clamped_pct": 100.0 * c["clamped_alpha"] / max(1, c["vertex_steps"]),
        "clamped_by_cause": c.get("clamped_alpha_by_cause"),
        "fallback_pct": 100.0 * c["insertion_fallbacks"] / max(1, inserted),
        "previous_row_insertions": c.get("previous_row_insertions"),
        "seed_shots_skipped": c.get("seed_shots_skipped"),
        "evaluations": c["field_evaluations"],
        "fallbacks_by_cause": c.get("insertion_fallbacks_by_cause"),
        "skipped_pct": 100.0 * c["skipped_vertex_steps"] / max(1, c["vertex_steps"]),
        "times_s": {k: t[k] for k in ("total", "alpha", "advance", "adapt", "stitch", "quality")
                    if k in t},
    }


def cell(value, form):
    """A figure as `form`, or "-" where the build that ran has no such figure."""
    return "-" if value is None else form % value


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--binary", default=os.path.join(here, "..", "build", "apps", "orthofront"))
    parser.add_argument("--baseline", help="another build (e.g. an older one), run with its defaults")
    parser.add_argument("--data", default=os.path.join(here, "..", "..", "shared", "datasets"))
    parser.add_argument("--json", help="also write the rows here")
    a = parser.parse_args()
    rows = []
    header = ("case", "variant", "verts", "quads%", "ang±10%", "spread", "folds", "nm", "tj",
              "degen", "rips", "stall", "gap faces", "boundary", "clamp%", "fallb%", "skip%", "shots skipped", "evals M", "total s", "alpha", "advance",
              "adapt", "stitch", "quality")
    print("| " + " | ".join(header) + " |")
    print("|" + "---|" * len(header))
    with tempfile.TemporaryDirectory() as work:
        for name, path, args in CASES:
            field = os.path.join(a.data, path)
            if not os.path.exists(field):
                print("| %s | skipped: %s not found |" % (name, field))
                continue
            runs = [(variant, a.binary, options) for variant, options in VARIANTS]
            if a.baseline:
                runs.insert(0, ("baseline", a.baseline, ""))
            for variant, binary, options in runs:
                try:
                    x = row(name, variant, run(binary, field, args, options, work))
                except subprocess.CalledProcessError as e:
                    if variant != "baseline":
                        raise
                    # An older build may not know this case's options.
                    print("| %s | %s | failed (exit %d): see its message above |" %
                          (name, variant, e.returncode))
                    continue
                rows.append(x)
                t = x["times_s"]
                cells = [name, variant, "%d" % x["vertices"], "%.1f" % x["quads_pct"],
                         "%.1f" % x["angles_within_10_pct"], "%.3f" % x["edge_spread"],
                         "%d" % x["folds"], "%d" % x["non_manifold_edges"],
                         "%d" % x["t_junctions"], "%d" % x["degenerate_faces"],
                         cell(x["fold_rips"], "%d"), cell(x["stall_cuts"], "%d"),
                         cell(x["gap_faces"], "%d"), cell(x["boundary_edges"], "%d"),
                         "%.1f" % x["clamped_pct"], "%.1f" % x["fallback_pct"],
                         "%.1f" % x["skipped_pct"], cell(x["seed_shots_skipped"], "%d"),
                         "%.2f" % (x["evaluations"] / 1e6)]
                cells += ["%.3f" % t.get(k, 0)
                          for k in ("total", "alpha", "advance", "adapt", "stitch", "quality")]
                print("| " + " | ".join(cells) + " |")
    print()
    for x in rows:
        if x["variant"] == "default":
            print("%s: clamped α by cause %s; insertion fallbacks by cause %s" % (
                x["case"], json.dumps(x["clamped_by_cause"]), json.dumps(x["fallbacks_by_cause"])))
    if a.json:
        with open(a.json, "w") as f:
            json.dump(rows, f, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
