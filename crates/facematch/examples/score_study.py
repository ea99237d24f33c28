#!/usr/bin/env python3
"""Scoring rules simulated on the per-view, per-pair distances that `score_study` writes.

    python3 crates/facematch/examples/score_study.py OUT/pairs.csv

For each set (tuning, held-out) the probes against their own set's gallery: rank-1, the equal
error rate and min(other persons) / max(same person), for the compare rule as committed and
for other view turns, pair combinations and cohort normalisations (T-norm: the probe's cohort
is the other set's gallery; Z-norm: a template's cohort is the other set's probes; S-norm:
the two averaged). The cohorts are other persons. Plain Python 3, no packages.
"""
import csv, math, statistics, sys

TURNS = ["m15", "p15", "m25", "p25", "m35", "p35", "m45", "p45"]
PAIRS = ["c", "r", "l"]
TEXT = ("set", "gallery", "probe", "template", "view")
rows = list(csv.DictReader(open(sys.argv[1])))
for r in rows:
    for k in r:
        if k not in TEXT:
            r[k] = float(r[k])


def ident(name):
    return name.split("-")[0]


def pair_distances(r, turns, min_angle=10.0):
    """`facematch::compare`'s choice: own below `min_angle`, else the nearest of `turns`
    (a failed pair of the view replaced by the own one)."""
    own = [r["own_" + p] for p in PAIRS]
    if not r["angle_own"] >= min_angle:
        return own
    near = [(r["off_" + t], t) for t in turns if not math.isnan(r["off_" + t])]
    if not near:
        return own
    t = min(near)[1]
    return [o if math.isnan(x) else x for x, o in zip((r[t + "_" + p] for p in PAIRS), own)]


def least(d, second=0.0):
    x = sorted(v for v in d if not math.isnan(v))
    if not x:
        return math.nan
    return x[0] if len(x) == 1 or second == 0 else (1 - second) * x[0] + second * x[1]


def figures(items):
    inf = lambda s: math.inf if math.isnan(s) else s
    best = {}
    for p, t, s in items:
        if p not in best or inf(s) < best[p][0]:
            best[p] = (inf(s), t)
    rank1 = sum(ident(t) == ident(p) for p, (s, t) in best.items()) / len(best)
    same = [inf(s) for p, t, s in items if ident(p) == ident(t)]
    other = [inf(s) for p, t, s in items if ident(p) != ident(t)]
    eer = 1.0
    for th in sorted({x for x in same + other if math.isfinite(x)}):
        frr = sum(x > th for x in same) / len(same)
        far = sum(x <= th for x in other) / len(other)
        eer = min(eer, max(frr, far))
    return rank1, eer, min(other) / max(same)


def cohort_scale(score, stat):
    out = {}
    for s in ("tuning", "held-out"):
        other = "held-out" if s == "tuning" else "tuning"
        per = {}
        for r in rows:
            if r["set"] == s and r["gallery"] == other and math.isfinite(score(r)):
                per.setdefault(r["probe"], []).append(score(r))
        out.update({(s, p): stat(v) for p, v in per.items()})
    return lambda r: score(r) / out[(r["set"], r["probe"])]


def template_cohort(score, stat):
    """Z-norm's scale of a template: `stat` of the other set's probes (other persons) against it."""
    out = {}
    for r in rows:
        if r["gallery"] != r["set"] and math.isfinite(score(r)):
            out.setdefault((r["gallery"], r["template"]), []).append(score(r))
    out = {k: stat(v) for k, v in out.items()}
    return lambda r: out[(r["set"], r["template"])]


def show(name, score):
    cells = []
    for s in ("tuning", "held-out"):
        items = [(r["probe"], r["template"], score(r)) for r in rows
                 if r["set"] == s and r["gallery"] == s]
        cells.append("%.3f / %.3f / %.2f" % figures(items))
    print("| %s | %s |" % (name, " | ".join(cells)))


print("| rule | tuning: rank-1 / EER / ratio | held-out: rank-1 / EER / ratio |")
print("|---|---|---|")
show("as compared (`score` column)", lambda r: r["score"])
show("own description only", lambda r: least([r["own_" + p] for p in PAIRS]))
for turns in (["15", "25", "35", "45"], ["15", "25", "35"], ["15", "35"], ["25", "45"],
              ["15", "45"], ["15"], ["25"], ["35"]):
    ts = [t for t in TURNS if t[1:] in turns]
    show("views at +-" + ", ".join(turns), lambda r, ts=ts: least(pair_distances(r, ts)))
for w in (0.25, 0.5):
    show("8 views, second pair weight %.2f" % w, lambda r, w=w: least(pair_distances(r, TURNS), w))
show("8 views, mean of the pairs",
     lambda r: statistics.fmean([x for x in pair_distances(r, TURNS) if not math.isnan(x)] or [math.nan]))
show("mean of both directions", lambda r: (r["score"] + r["rev_score"]) / 2)
for turns in (TURNS, ["m25", "p25"]):
    base = lambda r, ts=turns: least(pair_distances(r, ts))
    n = "8 views" if len(turns) == 8 else "views at +-25"
    show(n + ", T-norm by the cohort's median", cohort_scale(base, statistics.median))
    show(n + ", T-norm by the cohort's mean", cohort_scale(base, statistics.fmean))
base = lambda r: least(pair_distances(r, TURNS))
for name, stat in (("median", statistics.median), ("mean", statistics.fmean)):
    z = template_cohort(base, stat)
    t = cohort_scale(base, stat)
    show("8 views, Z-norm by the template's cohort " + name, lambda r, z=z: base(r) / z(r))
    show("8 views, S-norm (T and Z averaged) by the " + name,
         lambda r, z=z, t=t: 0.5 * (t(r) + base(r) / z(r)))
