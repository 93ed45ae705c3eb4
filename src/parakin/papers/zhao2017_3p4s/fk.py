"""Zhao 2017 §1.1, Fig. 3, Table 2: forward kinematics by a BP network + quasi-Newton hybrid,
and the benchmark that puts it beside every other solver (our addition).

Pipeline: ``samples`` (IK over the workspace) -> ``train`` (3-10-3 network, Levenberg-Marquardt)
-> ``table2`` (hybrid FK of Table 1's poses) and ``fk_benchmark``.
"""

from __future__ import annotations

import json
import sys
import time
from functools import partial
from pathlib import Path

import numpy as np
import pandas as pd

from parakin.claims import CI_LEVEL, REPRODUCED, Claim, judge, printed_value, run_summary
from parakin.config import rng, seed_for
from parakin.errors import ConfigError
from parakin.io import atomic_write_text, atomic_writer, write_and_draw, write_csv, write_table
from parakin.mechanisms import P3P4S
from parakin.nn.bp import plateau_epoch
from parakin.papers.runs import map_runs
from parakin.papers.sections import table_text
from parakin.papers.zhao2017_3p4s.common import KEY, artefact, table
from parakin.papers.zhao2017_3p4s.kinematics import table1_inputs
from parakin.registry import EXACT, ITERATIVE, Tolerance
from parakin.solvers import solve_fk
from parakin.workspace import sample_reachable

#: a trained network's set-up columns (compared exactly)
SETUP = ("samples", "hidden", "weights")
#: LM training follows another trajectory once a BLAS kernel rounds one product differently; the
#: trained network's test error is stable to within a factor of two, its weights and log are not
TRAINING = Tolerance.statistical(
    "network training: the per-epoch log is one chaotic trajectory (not compared); the "
    "test error of the trained network is compared within a factor of two",
    columns={c: (1.0, 0.0) for c in ("test_rms_m", "test_max_m", "test_p95_m", "test_e3_m")}
    | Tolerance.exactly(*SETUP),
    files=("extra_bp_training.csv", "extra_bp_training.png"),
)
#: the hybrid's quasi-Newton refinement converges to the same root from any nearby network guess
HYBRID = ITERATIVE.but(
    "the network's guess differs with the training (not compared, nor the iterates from it); the "
    "refined pose converges to eps = 1e-7 in the step, far below 1e-9 m in the pose",
    skip=("guess_x", "guess_y", "guess_z", "e3_guess", "e3"),
    columns={"iterations": (0.0, 1.0)},
    files=("table2_iterates.csv", "table2_iterates.md"),
)
#: solver statistics over seeded random inputs; PSO rows are chaotic searches
SOLVER_STATS = Tolerance.statistical(
    "solver statistics: success rates within 5 points (PSO is a chaotic search), "
    "median iterations within one; errors at round-off level and extremes not compared",
    columns={"n_accuracy": (0.0, 0.0), "success_rate": (0.0, 0.05), "median_nit": (0.0, 1.0)},
)

PAPER_TIME_MS = 20.0  # §1.1: "求解效率在20 ms以内"


def generated(config: dict) -> Path:
    """This paper's folder of generated (git-ignored) data."""
    return Path(config["generated_dir"]) / KEY


def network_path(config: dict) -> Path:
    return generated(config) / "bp_network.npz"


def _mech() -> P3P4S:
    """The geometry the paper states for Tables 1-2 (§1.1). FK of IK(pose) returns the pose for
    any geometry, so Table 2 does not depend on the Table 1 discrepancy."""
    return P3P4S.zhao2017()


# ---------------------------------------------------------------------------------- samples
@artefact(
    "samples",
    outputs=[],
    generated=["bp_samples.npz"],
    config=["zhao2017_3p4s.fk"],
    tolerance=EXACT,
)
def samples(config: dict, outdir: Path) -> list[Path]:
    """Training samples: poses uniform in the workspace box, strokes by the IK (eq 5).

    Unreachable poses are rejected (never NaN). Written with the sampling recorded (bounds,
    count, seed) to ``<generated>/zhao2017_3p4s/bp_samples.npz``.
    """
    cfg = config[KEY]["fk"]
    mech = _mech()
    lo, hi = mech.pose_bounds()
    poses = sample_reachable(mech, cfg["samples"], rng(config, f"{KEY}.samples"), bounds=(lo, hi))
    strokes = mech.ik(poses)
    path = generated(config) / "bp_samples.npz"

    def write(tmp: Path) -> None:
        with open(tmp, "wb") as fh:
            np.savez(
                fh,
                poses=poses,
                strokes=strokes,
                bounds_low=lo,
                bounds_high=hi,
                seed=seed_for(config, f"{KEY}.samples"),
                count=len(poses),
                parameters=json.dumps(mech.parameters()),
            )

    return [atomic_writer(path, write)]


# ---------------------------------------------------------------------------------- training
def draw_training(frame: pd.DataFrame, path: Path) -> Path:
    """extra_bp_training from its CSV (the LM log): RMS position error per epoch of the
    training, validation and test sets."""
    from parakin.plot import new_figure, save_figure, use_style

    cols = [c for c in ("train_rms_m", "val_rms_m", "test_rms_m") if c in frame.columns]
    with use_style():
        fig, ax = new_figure("single")
        for col, label in zip(cols, ("training", "validation", "test")):
            ax.semilogy(frame["epoch"], frame[col], label=label)
        ax.set_xlabel("Levenberg–Marquardt epoch")
        ax.set_ylabel("RMS position error (m)")
        ax.set_title("BP network 3-10-3 (Zhao 2017 §1.1)")
        ax.legend()
    return save_figure(fig, path)


@table(
    "train",
    "extra_bp_accuracy",
    "extra_bp_training.csv",
    "extra_bp_training.png",
    generated=["bp_network.npz", "bp_training_log.csv", "bp_training_summary.json"],
    needs=["zhao2017_3p4s:samples"],
    config=["zhao2017_3p4s.fk"],
    tolerance=TRAINING,
    threads=2,
    resources={"runtime": 30, "mem_mb": 2000},
    draws=[("extra_bp_training.png", "extra_bp_training.csv", draw_training)],
)
def train(config: dict, outdir: Path) -> list[Path]:
    """The paper's BP network (3 strokes -> 10 tanh -> 3 coordinates) trained by
    Levenberg-Marquardt with MATLAB trainlm's rules; weights and log to the generated folder,
    the training curve (extra_bp_training) and held-out accuracy (extra_bp_accuracy) to figures."""
    from parakin.nn import train_lm

    cfg = config[KEY]["fk"]
    data = np.load(generated(config) / "bp_samples.npz")

    every = max(1, int(cfg["max_epochs"]) // 10)  # a line per ~10 % of the epoch budget

    def progress(epoch: int, train_mse: float, val_mse: float) -> None:
        if epoch % every == 0 or epoch == 1:
            print(
                f"  train: LM epoch {epoch:4d}/{cfg['max_epochs']} ({100 * epoch // int(cfg['max_epochs'])} % of the "
                f"budget; stops earlier on validation): train mse {train_mse:.3e}, val mse {val_mse:.3e}",
                file=sys.stderr,
                flush=True,
            )

    def fit(strokes, poses, stream: str, report=None):
        return train_lm(
            strokes,
            poses,
            hidden=cfg["hidden"],
            seed=seed_for(config, stream),
            max_epochs=cfg["max_epochs"],
            val_fraction=cfg["val_fraction"],
            test_fraction=cfg["test_fraction"],
            progress=report,
        )

    net, log, summary = fit(data["strokes"], data["poses"], f"{KEY}.train", progress)
    paths = [net.save(network_path(config))]
    paths.append(write_csv(log, generated(config) / "bp_training_log.csv"))
    paths.append(
        atomic_write_text(
            generated(config) / "bp_training_summary.json",
            json.dumps(summary, indent=2, sort_keys=True) + "\n",
        )
    )
    keys = ("epochs", "stop_reason", "best_epoch", "test_rms_m", "test_max_m", "test_p95_m")
    e3 = "test_mean_abs_axis_m"  # the paper's E_3 (Table 2's measure) averaged over the test set
    lo, hi = data["bounds_low"], data["bounds_high"]
    rows = [
        {
            "box": "workspace (pipeline's network)",
            "low": _fmt_box(lo),
            "high": _fmt_box(hi),
            "samples": int(data["count"]),
            **{k: summary[k] for k in keys},
            "test_e3_m": summary[e3],
        }
    ]
    # The paper does not say where it sampled; the network's accuracy depends on it. The same
    # training on smaller boxes shows how (one network per box, same sample count and settings).
    mech = _mech()
    for box in cfg["accuracy_boxes"]:
        poses = sample_reachable(
            mech,
            cfg["samples"],
            rng(config, f"{KEY}.samples.{box['name']}"),
            bounds=(box["low"], box["high"]),
        )
        _, _, s_box = fit(mech.ik(poses), poses, f"{KEY}.train.{box['name']}")
        rows.append(
            {
                "box": box["name"],
                "low": _fmt_box(box["low"]),
                "high": _fmt_box(box["high"]),
                "samples": len(poses),
                **{k: s_box[k] for k in keys},
                "test_e3_m": s_box[e3],
            }
        )
    acc = pd.DataFrame(rows)
    acc.insert(4, "hidden", cfg["hidden"])
    acc.insert(5, "weights", net.n_weights)
    paths += write_table(
        acc,
        outdir / "extra_bp_accuracy",
        title="BP network accuracy on held-out test sets",
        notes="Errors: |predicted - true| platform position (m, 3-D) on samples the training never saw "
        "(paper §1.1: 'output accuracy at the 10^-4 level', sampling region and error measure not "
        "stated); test_e3_m: the mean absolute coordinate error, Table 2's E_3 averaged over the test "
        "set. Row 1 is the network the hybrid solver uses; the others retrain on smaller boxes of "
        "poses (m).",
    )
    paths += _training_figure(log, outdir)
    return paths


def _fmt_box(v) -> str:
    return "(" + ", ".join(f"{float(x):g}" for x in v) + ")"


def _training_figure(log: pd.DataFrame, outdir: Path) -> list[Path]:
    """extra_bp_training.{csv,png}: the log written, read back and drawn from the CSV alone."""
    return write_and_draw(log, outdir / "extra_bp_training.csv", draw_training)


# ---------------------------------------------------------------------------------- convergence
#: per region only what is stable is compared: the set-up exactly, the 99 % confidence interval of
#: the median test error over the restarts by overlap and the median p95 / E_3 within a factor of
#: two; each run's curve is one chaotic trajectory (another BLAS kernel, another number of epochs)
#: and is not compared, nor is how many runs converged (a run near the rule's threshold may stop
#: an epoch window later on another machine)
CONVERGENCE = Tolerance.statistical(
    "network training to convergence: the per-epoch curves are chaotic trajectories (not "
    "compared); per region the set-up, the overlap of the 99 % confidence intervals of the "
    "median test error over the restarts and the median p95 and E_3 within a factor of two are",
    columns=Tolerance.exactly(*SETUP, "restarts", "window", "min_improvement", "max_epochs")
    | {c: (1.0, 0.0) for c in ("test_p95_median_m", "test_e3_median_m")},
    intervals=(("test_rms_ci_low_m", "test_rms_ci_high_m"),),
    files=("extra_bp_convergence_curves.csv", "extra_bp_convergence.png"),
)
#: the region of the pipeline's own network (the mechanism's workspace box)
OURS = "workspace"


def convergence_settings(config: dict) -> dict:
    """``config[KEY]["network_convergence"]``, checked, with ``regions``: name -> (low, high), the
    workspace box first, then every ``fk.accuracy_boxes`` entry."""
    try:
        cfg = dict(config[KEY]["network_convergence"])
    except (KeyError, TypeError):
        raise ConfigError(f"config has no '{KEY}.network_convergence' section") from None
    lo, hi = _mech().pose_bounds()
    regions = {OURS: (lo, hi)}
    for box in config[KEY]["fk"]["accuracy_boxes"]:
        regions[box["name"]] = (np.asarray(box["low"], float), np.asarray(box["high"], float))
    if cfg.get("paper_region") not in regions or cfg["paper_region"] == OURS:
        raise ConfigError(
            f"{KEY}.network_convergence.paper_region = {cfg.get('paper_region')!r} must name one "
            f"of the boxes in {KEY}.fk.accuracy_boxes: {', '.join(list(regions)[1:]) or 'none'}"
        )
    cfg["regions"] = regions
    return cfg


def draw_bp_convergence(frame: pd.DataFrame, path: Path) -> Path:
    """extra_bp_convergence from its curves CSV: the validation RMS error per LM epoch of every
    run on every region until the convergence rule stopped it, the test error of each returned
    (best-validation) network at its epoch, and the paper's "1e-4 level" as the band within half a
    decade of it."""
    from parakin.plot import new_figure, save_figure, use_style

    paper = float(frame["paper_accuracy_m"].iloc[0])
    with use_style():
        fig, ax = new_figure("single_tall")
        ax.axhspan(
            paper / 10**0.5,
            paper * 10**0.5,
            color="0.88",
            lw=0,
            label=f"paper: {paper:g} level (±½ decade)",
        )
        for k, (region, g) in enumerate(frame.groupby("region", sort=False)):
            color = f"C{k}"
            for j, (_, run) in enumerate(g.groupby("restart", sort=False)):
                ax.semilogy(
                    run["epoch"],
                    run["val_rms_m"],
                    color=color,
                    lw=0.8,
                    label=f"{region}: validation" if j == 0 else None,
                )
            best = g[g["best"]]
            ax.plot(
                best["epoch"], best["test_rms_m"], "o", color=color, ms=4, mfc="none",
                label=f"{region}: test, returned network",
            )  # fmt: skip
        ax.set_xlabel("Levenberg–Marquardt epoch")
        ax.set_ylabel("RMS position error (m)")
        ax.set_title("Beyond the paper: BP 3-10-3 network\ntrained to convergence per region")
        ax.legend(fontsize="x-small")
    return save_figure(fig, path)


def _convergence_run(config_json: str, name: str, k: int) -> dict:
    """One training to convergence of the 3-10-3 network on region ``name`` from seed ``k`` (the
    region's samples are the same for every ``k``): its summary and its per-epoch curve."""
    from parakin.nn import train_lm

    config = json.loads(config_json)
    cfg, fk_cfg, mech = convergence_settings(config), config[KEY]["fk"], _mech()
    lo, hi = cfg["regions"][name]
    poses = sample_reachable(
        mech, cfg["samples"], rng(config, f"{KEY}.convergence.samples.{name}"), bounds=(lo, hi)
    )
    net, log, s = train_lm(
        mech.ik(poses),
        poses,
        hidden=fk_cfg["hidden"],
        seed=seed_for(config, f"{KEY}.convergence.train.{name}.{k}"),
        max_epochs=cfg["max_epochs"],
        max_fail=cfg["max_epochs"] + 1,  # MATLAB's val_fail stop off: the rule decides
        val_fraction=fk_cfg["val_fraction"],
        test_fraction=fk_cfg["test_fraction"],
        plateau_window=cfg["window"],
        plateau_improvement=cfg["min_improvement"],
        num_threads=1,
    )
    curve = {
        "restart": k,
        "epoch": log["epoch"].tolist(),
        "train_rms_m": log["train_rms_m"].tolist(),
        "val_rms_m": log["val_rms_m"].tolist(),
        "test_rms_m": log["test_rms_m"].tolist(),
        "best": (log["epoch"] == s["best_epoch"]).tolist(),
        "stop_reason": s["stop_reason"],
    }
    return {"summary": s, "curve": curve, "samples": len(poses), "weights": net.n_weights}


def _convergence_row(name: str, box, mine: list[dict], config: dict, printed: str) -> dict:
    """The row of extra_bp_convergence for region ``name`` (``box``: its low and high corners)
    from its trainings ``mine`` (each as :func:`_convergence_run` returns it)."""
    cfg = convergence_settings(config)
    fk_cfg = config[KEY]["fk"]
    lo, hi = box
    runs = [r["summary"] for r in mine]
    rms = np.array([s["test_rms_m"] for s in runs])
    e3 = float(np.median([s["test_mean_abs_axis_m"] for s in runs]))
    stats = run_summary(rms)
    role = (
        "ours (the pipeline's network)"
        if name == OURS
        else "the paper's working poses"
        if name == cfg["paper_region"]
        else "a smaller box"
    )
    return {
        "region": name,
        "role": role,
        "low": _fmt_box(lo),
        "high": _fmt_box(hi),
        "samples": mine[0]["samples"],
        "hidden": fk_cfg["hidden"],
        "weights": mine[0]["weights"],
        "restarts": len(runs),
        "window": cfg["window"],
        "min_improvement": cfg["min_improvement"],
        "max_epochs": cfg["max_epochs"],
        "converged_runs": sum(s["stop_reason"] != "max_epochs" for s in runs),
        "epochs_median": float(np.median([s["epochs"] for s in runs])),
        "test_rms_median_m": stats["median"],
        "test_rms_ci_low_m": stats["ci_low"],
        "test_rms_ci_high_m": stats["ci_high"],
        "test_rms_min_m": stats["min"],
        "test_rms_max_m": stats["max"],
        "test_p95_median_m": float(np.median([s["test_p95_m"] for s in runs])),
        "test_e3_median_m": e3,
        "range_at_paper_level": judge(
            printed, stats["median"], kind="order", spread=(stats["min"], stats["max"])
        )
        == REPRODUCED,
        "e3_median_at_paper_level": judge(printed, e3, kind="order") == REPRODUCED,
    }


def _convergence_notes(cfg: dict, fk_cfg: dict, printed: str) -> str:
    """The notes of extra_bp_convergence: the sampling, the convergence rule, the error measures."""
    return (
        f"Each region: {cfg['samples']} IK samples uniform in the box (m), the 3-{fk_cfg['hidden']}-3 network "
        f"trained {cfg['restarts']} times from different seeds, "
        f"{1 - fk_cfg['val_fraction'] - fk_cfg['test_fraction']:.0%}/{fk_cfg['val_fraction']:.0%}/"
        f"{fk_cfg['test_fraction']:.0%} split, LM as MATLAB trainlm but without its 6-failure validation stop. "
        f"Convergence rule, fixed before the runs: stop when the best validation RMS error has not improved by "
        f"{cfg['min_improvement']:.0%} over the last {cfg['window']} epochs ('mu_max' and 'min_grad' also mean no "
        f"further progress); a run reaching the cap of {cfg['max_epochs']} epochs has not converged. Errors: "
        "|predicted - true| platform position (m, 3-D) of each best-validation network on its test set; median, "
        f"its {100 * CI_LEVEL:g} % confidence interval (order statistics; with 10 runs the whole range), min and max "
        "over the runs; test_e3_median_m: median over the runs of the mean absolute coordinate "
        "error (Table 2's E_3 averaged over the test set). The paper (§1.1) claims a "
        f"'{printed} level' without stating the region or the error measure; range_at_paper_level: some run "
        "within half a decade of it (the reference CSV's tolerance; the paper reports one training), "
        "e3_median_at_paper_level: the median E_3 within half a decade. Runs side by side on the job's "
        "cores, each on one thread from its own seed."
    )


@table(
    "network_convergence",
    "extra_bp_convergence",
    "extra_bp_convergence_curves.csv",
    "extra_bp_convergence.png",
    config=["zhao2017_3p4s.fk", "zhao2017_3p4s.network_convergence"],
    tolerance=CONVERGENCE,
    threads=2,
    resources={"runtime": 20, "mem_mb": 2000},
    caption="the BP network trained to convergence on each sampling region (§1.1's 1e-4 level)",
    draws=[("extra_bp_convergence.png", "extra_bp_convergence_curves.csv", draw_bp_convergence)],
)
def network_convergence(config: dict, outdir: Path) -> list[Path]:
    """The paper's 3-10-3 network trained by the same LM on each candidate sampling region, from
    ``restarts`` seeds, each until a convergence rule fixed in the config stops it (the best
    validation RMS error has not improved by ``min_improvement`` over ``window`` epochs;
    ``max_epochs`` is a cap a converged run never reaches). Shows whether the network-accuracy gap
    (§1.1: "1e-4 level") comes from the epoch limit of the pipeline's training or from the region
    sampled (docs/zhao2017_3p4s.md#s4.5)."""
    cfg = convergence_settings(config)
    printed = printed_value(_ref(), "text_s1.1", "network_accuracy")
    tasks = [
        (json.dumps(config, sort_keys=True, default=list), name, k)
        for name in cfg["regions"]
        for k in range(cfg["restarts"])
    ]
    results = map_runs(_convergence_run, tasks, label="network_convergence: trainings")
    rows, curves = [], []
    for name, box in cfg["regions"].items():
        mine = [r for (_, region, _), r in zip(tasks, results) if region == name]
        curves += [
            pd.DataFrame({"region": name, **r["curve"], "paper_accuracy_m": float(printed)})
            for r in mine
        ]
        rows.append(_convergence_row(name, box, mine, config, printed))
    tab = pd.DataFrame(rows)
    paths = write_table(
        tab,
        outdir / "extra_bp_convergence",
        title="BP network trained to convergence on each sampling region",
        notes=_convergence_notes(cfg, config[KEY]["fk"], printed),
    )
    paths += write_and_draw(
        pd.concat(curves, ignore_index=True),
        outdir / "extra_bp_convergence_curves.csv",
        draw_bp_convergence,
        outdir / "extra_bp_convergence.png",
    )
    return paths


# ---------------------------------------------------------------------------------- Table 2
def _median_time_ms(fn, repeats: int) -> float:
    fn()  # warm-up
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return float(np.median(times) * 1e3)


@table(
    "table2",
    "table2",
    "table2_iterates.csv",
    "table2_iterates.md",
    needs=["zhao2017_3p4s:train"],
    config=["zhao2017_3p4s.fk"],
    tolerance=HYBRID,
)
def table2(config: dict, outdir: Path) -> list[Path]:
    """Table 2: the hybrid FK of each Table 1 case, from the exact IK strokes of its pose.

    E_3 = (|dx| + |dy| + |dz|) / 3, the mean absolute pose error: the reading that reproduces
    rows 1, 3, 5 of the printed table from its own solved values (docs/zhao2017_3p4s.md#s2). Times are the median
    of ``timing_repeats`` single solves (the paper: < 20 ms on a 3.2 GHz PC).
    """
    from parakin.nn import BPNetwork

    cfg = config[KEY]["fk"]
    mech = _mech()
    net = BPNetwork.load(network_path(config))
    poses, _ = table1_inputs()

    def solve(q):
        return solve_fk(
            mech,
            q,
            method="hybrid",
            network=net,
            eps=cfg["epsilon"],
            tol=0.0,
            maxiter=cfg["maxiter"],
        )

    rows = []
    for k, pose in enumerate(poses):
        q = mech.ik(pose)  # exact strokes: the printed ones are rounded to 0.01 m
        guess = net.predict(q)
        res = solve(q)
        t_ms = _median_time_ms(lambda q=q: solve(q), cfg["timing_repeats"])
        rows.append(
            {
                "case": k + 1,
                "target_x": pose[0],
                "target_y": pose[1],
                "target_z": pose[2],
                "l1": q[0],
                "l2": q[1],
                "l3": q[2],
                "guess_x": guess[0],
                "guess_y": guess[1],
                "guess_z": guess[2],
                "e3_guess": float(np.mean(np.abs(guess - pose))),
                "solved_x": res.x[0],
                "solved_y": res.x[1],
                "solved_z": res.x[2],
                "e3": float(np.mean(np.abs(res.x - pose))),
                "iterations": int(res.nit),
                "converged": bool(res.success),
                "time_ms": t_ms,
            }
        )
    tab = pd.DataFrame(rows)
    iterates = _iterates(mech, net, poses, cfg)
    wide = _table2_markdown(tab)
    notes = (
        f"Hybrid FK: BP network guess, then Broyden's quasi-Newton method until the step is below eps = {cfg['epsilon']:g} m "
        "(the paper's 'iteration error'). Inputs: the exact IK strokes of each Table 1 pose (stated geometry). "
        "E_3 = mean |pose error| over x, y, z. Times: median of single solves on this machine "
        "(the paper: < 20 ms at 3.2 GHz; its per-row times are lost in the extraction)."
    )
    return write_table(
        tab,
        outdir / "table2",
        title="Table 2 — hybrid forward kinematics",
        notes=notes,
        markdown=wide,
    ) + write_table(
        iterates,
        outdir / "table2_iterates",
        title="Table 2 — E_3 of every iterate of the hybrid's refinement",
        notes=(
            f"Each case: the iterates of Broyden's method from the network's guess (iteration 0) until the "
            f"paper's rule stops it (step below eps = {cfg['epsilon']:g} m). E_3 = mean |pose error| over x, y, z "
            "of that iterate; step_m: the length of the step that produced it. The printed E_3 is the error "
            "of the paper's stopped iterate: it depends on where its (unprinted) solver stood when its step "
            "fell below eps, anywhere from about eps down to round-off (ours, a step later, is at round-off). "
            "What compares across solvers is the accuracy the rule guarantees: E_3 at most the printed value "
            "(a bound; data/reference)."
        ),
        floatfmt=".3g",
    )


def _table2_markdown(tab: pd.DataFrame) -> pd.DataFrame:
    """Table 2's Markdown view: ours beside the paper's printed E_3 and iterations."""
    ref_e3 = [printed_value(_ref(), "table2", f"case{k}.e3") for k in range(1, 6)]
    ref_it = [printed_value(_ref(), "table2", f"case{k}.iterations") for k in range(1, 6)]
    return pd.DataFrame(
        {
            "case": tab["case"],
            "target (x, y, z) / m": [
                f"({r.target_x:g}, {r.target_y:g}, {r.target_z:g})" for r in tab.itertuples()
            ],
            "network guess E_3 / m": [f"{v:.2e}" for v in tab["e3_guess"]],
            "solved x_p / m": [f"{v:.10f}" for v in tab["solved_x"]],
            "solved y_p / m": [f"{v:.10f}" for v in tab["solved_y"]],
            "solved z_p / m": [f"{v:.10f}" for v in tab["solved_z"]],
            "E_3 / m (paper)": ref_e3,
            "E_3 / m (ours)": [f"{v:.2e}" for v in tab["e3"]],
            "iterations (paper)": ref_it,
            "iterations (ours)": tab["iterations"],
            "time / ms (ours)": [f"{v:.3f}" for v in tab["time_ms"]],
        }
    )


def _iterates(mech: P3P4S, net, poses: np.ndarray, cfg: dict) -> pd.DataFrame:
    """E_3 of every iterate of the hybrid's refinement for each pose (the solve stopped after
    0, 1, ... iterations, until it stops by itself)."""
    rows = []
    for case, pose in enumerate(poses, start=1):
        q, prev, k = mech.ik(pose), None, 0
        while True:
            res = solve_fk(
                mech, q, method="hybrid", network=net, eps=cfg["epsilon"], tol=0.0, maxiter=k
            )
            rows.append(
                {
                    "case": case,
                    "iteration": k,
                    "e3_m": float(np.mean(np.abs(res.x - pose))),
                    "step_m": float(np.linalg.norm(res.x - prev)) if prev is not None else np.nan,
                    "stopped_by_rule": bool(res.success),
                }
            )
            if res.success or k >= cfg["maxiter"]:
                break
            prev, k = res.x, k + 1
    return pd.DataFrame(rows)


def _ref() -> pd.DataFrame:
    from parakin.claims import load_reference

    return load_reference(KEY)


# ---------------------------------------------------------------------------------- benchmark
#: ``@_bench_table(name, stem, ...)``: a benchmark table of the trained network's solvers
_bench_table = partial(table, needs=[f"{KEY}:train"], config=[f"{KEY}.fk", f"{KEY}.bench"])


@_bench_table("fk_benchmark", "fk_benchmark", tolerance=SOLVER_STATS)
def fk_benchmark(config: dict, outdir: Path) -> list[Path]:
    """Every FK solver on the same random reachable strokes (our addition to §1.1)."""
    from parakin.bench import SolverSpec, bench_fk
    from parakin.nn import load_network

    cfg = config[KEY]["bench"]
    eps = config[KEY]["fk"]["epsilon"]
    mech = _mech()
    net = load_network(
        network_path(config), fallback=True
    )  # `parakin bench` before any pipeline run
    gen = rng(config, f"{KEY}.bench")
    x1 = sample_reachable(mech, cfg["n_single"], gen)
    x2 = sample_reachable(mech, cfg["n_batch"], gen)
    specs = [
        SolverSpec(
            "hybrid (network + Broyden, eps 1e-7)",
            "hybrid",
            {"network": net, "eps": eps},
            start="network",
        ),
        SolverSpec(
            "hybrid (network + BFGS, eps 1e-7)",
            "hybrid",
            {"network": net, "eps": eps, "refine": "bfgs"},
            start="network",
        ),
        SolverSpec("quasi-Newton (BFGS) from home", "bfgs"),
        SolverSpec("Broyden from home", "broyden"),
        SolverSpec("Newton-Raphson from home", "newton"),
        SolverSpec("Levenberg-Marquardt from home", "lm"),
        SolverSpec("scipy.optimize.root (hybr), loop", "scipy-root", batched=False),
        SolverSpec("closed form (three spheres)", "closed-form", start="-"),
    ]
    df = bench_fk(
        mech,
        specs,
        (mech.ik(x1), x1),
        (mech.ik(x2), x2),
        tol=cfg["tol"],
        maxiter=cfg["maxiter"],
        success_tol=cfg["success_tol"],
        repeats=cfg["repeats"],
        progress=lambda label: print(f"  bench: {label}", file=sys.stderr),
    )
    df["speedup_vs_paper_20ms"] = PAPER_TIME_MS * 1e3 / df["median_latency_us"]
    md = pd.DataFrame(
        {
            "solver": df["solver"],
            "success": [f"{v:.1%}" for v in df["success_rate"]],
            "median / max error (m)": [
                f"{a:.1e} / {b:.1e}" for a, b in zip(df["median_err_m"], df["max_err_m"])
            ],
            "iterations (median / max)": [
                f"{a:g} / {b}" for a, b in zip(df["median_nit"], df["max_nit"])
            ],
            "single solve (µs, median)": [f"{v:.0f}" for v in df["median_latency_us"]],
            "batched (solves/s)": [
                f"{v:.3g}" + ("" if b else " (loop)")
                for v, b in zip(df["throughput_per_s"], df["batched"])
            ],
            "× scipy root (single)": [f"{v:.2f}" for v in df["speedup_single"]],
            "× scipy root (per solve, batched)": [f"{v:.3g}" for v in df["speedup_per_solve"]],
            "× paper's 20 ms": [f"{v:.0f}" for v in df["speedup_vs_paper_20ms"]],
        }
    )
    notes = (
        f"Same seeded random reachable strokes for every solver: {cfg['n_single']} solved one per call (latency), "
        f"{cfg['n_batch']} in one batched call (accuracy, throughput; best of {cfg['repeats']}). Success = converged "
        f"and within {cfg['success_tol']:g} m of the true pose. Starts: the home pose (0, 0, 0.592) m, or the network's "
        "guess for the hybrid. Timings are wall-clock on this machine; ratios are measured in the same run."
    )
    return write_table(
        df,
        outdir / "fk_benchmark",
        title="Forward kinematics of the 3-P(4S): every solver",
        notes=notes,
        markdown=md,
    )


# ---------------------------------------------------------------------------------- failures
#: the library's BFGS (Gauss-Newton start, analytic gradient) in extra_qn_failures
BFGS_LIBRARY = "BFGS from home, Gauss-Newton start (the library's)"
#: the textbook BFGS variants set up beside it (:mod:`.bfgs_variants`): label -> (start, gradient)
BFGS_VARIANTS = {
    "BFGS from home, identity start": ("identity", "analytic"),
    "BFGS from home, identity start, central-difference gradient": ("identity", "central"),
    "BFGS from home, identity start, forward-difference gradient": ("identity", "forward"),
}
#: the quasi-Newton rows of extra_qn_failures that are readings of conclusion (1)'s claim (the
#: forward-difference BFGS is not: its failures are its gradient's accuracy floor, short_of_tol)
QN_READINGS = (
    BFGS_LIBRARY,
    "BFGS from home, identity start",
    "BFGS from home, identity start, central-difference gradient",
    "Broyden from home",
)
#: the regions of extra_qn_failures that are readings (the height bands partition the whole workspace)
QN_REGIONS = ("Table 1's box", "benchmark box", "whole workspace")
#: a failure within this distance of the sampled pose stopped near it (short_of_tol): 100 times the
#: success criterion, declared with issue 45 before the runs
NEAR_TOL = 1e-6

#: failures of a deterministic solver over seeded poses: a pose near a basin's edge may flip with
#: the rounding of one step, so the failure rates are compared by the overlap of their 95 %
#: (Clopper-Pearson) intervals; the sample counts exactly
FAILURES = Tolerance.statistical(
    "failure counts over seeded poses: the number of poses exactly, the failure rates by the "
    "overlap of their 95 % intervals (a pose at a basin's edge may flip with one rounding)",
    columns={"poses": (0.0, 0.0)},
    intervals=(("rate_ci_low", "rate_ci_high"),),
)


def working_mode_poses(
    mech: P3P4S, n: int, g: np.random.Generator, bounds: tuple, max_rounds: int = 200
) -> np.ndarray:
    """``n`` poses uniform in the box ``bounds`` on the paper's working mode: reachable, and the
    pose the closed-form FK (the upper sphere intersection) returns for its own strokes (below it
    the same strokes assemble a second time, the lower intersection)."""
    from parakin.solvers.result import rowwise

    kept, count = [], 0
    for _ in range(max_rounds):
        if count >= n:
            break
        x = sample_reachable(mech, max(2 * (n - count), 64), g, bounds=bounds, max_rounds=1000)
        back = rowwise(lambda q: mech.fk(q), mech.ik(x), tail=(3,))
        with np.errstate(invalid="ignore"):
            x = x[np.max(np.abs(back - x), axis=-1) <= 1e-9]
        kept.append(x)
        count += len(x)
    if count < n:
        raise ValueError(f"only {count} of {n} working-mode poses found in the box {bounds}")
    return np.concatenate(kept)[:n]


def failure_settings(config: dict) -> dict:
    """``config[KEY]["failures"]``, checked."""
    try:
        cfg = config[KEY]["failures"]
    except (KeyError, TypeError):
        raise ConfigError(f"config has no '{KEY}.failures' section") from None
    boxes = {b["name"]: b for b in config[KEY]["fk"]["accuracy_boxes"]}
    if cfg.get("paper_box") not in boxes:
        raise ConfigError(
            f"{KEY}.failures.paper_box = {cfg.get('paper_box')!r} must name one of the boxes in "
            f"{KEY}.fk.accuracy_boxes: {', '.join(boxes) or 'none'}"
        )
    z = cfg.get("z_bands")
    if not (isinstance(z, list) and len(z) >= 2 and all(a < b for a, b in zip(z, z[1:]))):
        raise ConfigError(f"{KEY}.failures.z_bands = {z!r} must be >= 2 increasing heights (m)")
    return {
        **cfg,
        "paper_box_bounds": (boxes[cfg["paper_box"]]["low"], boxes[cfg["paper_box"]]["high"]),
    }


@table(
    "qn_failures",
    "extra_qn_failures",
    needs=["zhao2017_3p4s:train"],
    config=["zhao2017_3p4s.fk", "zhao2017_3p4s.bench", "zhao2017_3p4s.failures"],
    tolerance=FAILURES,
    resources={"runtime": 10, "mem_mb": 2000},
    caption="quasi-Newton from the home pose, region by region: how often and how it fails",
)
def qn_failures(config: dict, outdir: Path) -> list[Path]:
    """Conclusion (1), quasi-Newton "strongly affected by the initial value": Broyden, BFGS and
    Newton from the home pose, and the hybrid, on uniform working-mode poses of the box of Table 1's
    poses, of the benchmark's box and of the whole reachable workspace (a cube about home that
    holds it) and its height bands; per region the failure rate with its 95 % interval and the
    kind of failure (not converged, or converged to the other assembly of the same strokes)."""
    from parakin.nn import load_network
    from parakin.papers.failures import failure_table
    from parakin.papers.zhao2017_3p4s.bfgs_variants import bfgs_variant

    cfg, bench = failure_settings(config), config[KEY]["bench"]
    mech, n = _mech(), int(cfg["samples"])
    home = mech.home()
    cube = (home - cfg["cube_half_width"], home + cfg["cube_half_width"])
    g = rng(config, f"{KEY}.failures")
    whole = working_mode_poses(mech, n * (len(cfg["z_bands"]) - 1), g, cube)
    regions = {
        "Table 1's box": working_mode_poses(mech, n, g, cfg["paper_box_bounds"]),
        "benchmark box": working_mode_poses(mech, n, g, mech.pose_bounds()),
        "whole workspace": whole[:n],
    }
    for lo, hi in zip(cfg["z_bands"], cfg["z_bands"][1:]):
        band = (np.r_[cube[0][:2], lo], np.r_[cube[1][:2], hi])
        regions[f"z {lo:g} to {hi:g} m"] = working_mode_poses(mech, n, g, band)
    net = load_network(network_path(config), fallback=True)
    eps = config[KEY]["fk"]["epsilon"]
    solvers = {
        "Broyden from home": {"method": "broyden"},
        BFGS_LIBRARY: {"method": "bfgs"},
        **{
            label: partial(bfgs_variant, mech, start=start, gradient=gradient)
            for label, (start, gradient) in BFGS_VARIANTS.items()
        },
        "Newton-Raphson from home": {"method": "newton"},
        "hybrid (network + Broyden)": {"method": "hybrid", "network": net, "eps": eps},
    }
    tab = failure_table(
        mech,
        regions,
        solvers,
        x0=home,
        success_tol=bench["success_tol"],
        tol=bench["tol"],
        maxiter=bench["maxiter"],
        near_tol=NEAR_TOL,
    )
    span = np.ptp(whole, axis=0)
    notes = (
        f"Per region {n} poses uniform on the working mode (the upper sphere intersection of eq. 5's "
        "strokes: the pose the closed-form FK returns; beneath it the same strokes assemble again). "
        f"Whole workspace: a cube of half-width {cfg['cube_half_width']:g} m about home holds every "
        f"sampled working-mode pose (they span {span[0]:.2f} x {span[1]:.2f} x {span[2]:.2f} m); height "
        f"bands of that cube from z = {cfg['z_bands'][0]:g} to {cfg['z_bands'][-1]:g} m. Every solver starts "
        f"from the home pose {tuple(round(float(v), 3) for v in home)} m (the hybrid from its network's guess; the "
        f"network was trained on the benchmark box only). Failure: not within {bench['success_tol']:g} m of "
        f"the sampled pose; not_converged: the solver gave up; another_assembly: converged to another pose "
        f"with the same strokes; short_of_tol: failures within {NEAR_TOL:g} m of the sampled pose (stopped "
        "near it, short of the accuracy: a stopping rule or an inexact gradient, not another basin). "
        "Rates with exact (Clopper-Pearson) 95 % intervals. BFGS in four variants, every other setting "
        f"(line search, update, stop at a residual of {bench['tol']:g} m, at most {bench['maxiter']} "
        "iterations, the answer check) the library's: its own start from the Gauss-Newton inverse "
        "Hessian with the analytic gradient (its first step is a Newton step), and the textbook start "
        "from the identity with the analytic gradient, a central-difference gradient (scipy's "
        "'3-point') and a forward-difference one (scipy's default '2-point': its error of order "
        "1e-8 m stalls it near the pose, which shows as short_of_tol, not as a dependence on the "
        "start; it is not one of the verdict's readings). The paper does not say which quasi-Newton "
        "it uses; the verdict (report row conclusion/quasi_newton.failure_rate_from_home) takes the "
        "weakest of Broyden and the first three BFGS rows over Table 1's box, the benchmark box and "
        "the whole workspace."
    )
    return write_table(
        tab,
        outdir / "extra_qn_failures",
        title="Quasi-Newton from home: failures by region",
        notes=notes,
    )


# ---------------------------------------------------------------------------------- speed per solve
#: iteration counts and evaluation counts are deterministic from seeded inputs (a step at the
#: threshold may add one); the times are this machine's and never compared
SPEED = Tolerance.statistical(
    "per-solve speed: the median iterations within one; times (this machine, this load) not "
    "compared, their ratio decides only where it is far from 1",
    columns={"inputs": (0.0, 0.0), "median_nit": (0.0, 1.0)},
)


GUESS_THEN_BROYDEN = "network guess, then Broyden (no reachability check)"


def _interleaved_us(calls: dict, inputs: np.ndarray, rounds: int) -> dict[str, float]:
    """Median time (µs) of one call per input of each entry of ``calls``, the entries taking turns
    on every input (so that load on a shared machine falls on all of them alike)."""
    for f in calls.values():
        f(inputs[0])  # warm-up
    times = {k: [] for k in calls}
    for _ in range(rounds):
        for q in inputs:
            for k, f in calls.items():
                t0 = time.perf_counter()
                f(q)
                times[k].append(time.perf_counter() - t0)
    return {k: float(np.median(v)) * 1e6 for k, v in times.items()}


@_bench_table(
    "hybrid_speed",
    "extra_hybrid_speed",
    tolerance=SPEED,
    caption="the hybrid against quasi-Newton from home, per solve: iterations and time in one run",
)
def hybrid_speed(config: dict, outdir: Path) -> list[Path]:
    """Conclusion (1), the hybrid "more efficient than quasi-Newton": on the same random inputs,
    in one run, the hybrid (network guess + Broyden) against Broyden from the home pose, with the
    hybrid taken apart (the network's guess alone, Broyden from that guess alone): iterations and
    function evaluations per solve (machine-independent) and the time per solve of each, the calls
    taking turns on every input."""
    from parakin.nn import load_network

    cfg, eps = config[KEY]["bench"], config[KEY]["fk"]["epsilon"]
    mech = _mech()
    net = load_network(network_path(config), fallback=True)
    x = sample_reachable(mech, cfg["n_single"], rng(config, f"{KEY}.hybrid_speed"))
    q = mech.ik(x)
    home = mech.home()
    opts = {"tol": cfg["tol"], "maxiter": cfg["maxiter"]}
    solves = {
        "hybrid (network + Broyden)": lambda v: solve_fk(
            mech, v, method="hybrid", network=net, eps=eps, **opts
        ),
        "Broyden from home": lambda v: solve_fk(mech, v, method="broyden", x0=home, **opts),
        GUESS_THEN_BROYDEN: lambda v: solve_fk(
            mech, v, method="broyden", x0=net.predict(v), xtol=eps, **opts
        ),
    }
    times = _interleaved_us({**solves, "network guess alone": net.predict}, q, cfg["repeats"])
    rows = []
    for label, f in solves.items():
        res = [f(v) for v in q]
        rows.append(
            {
                "computation": label,
                "inputs": len(q),
                "median_nit": float(np.median([r.nit for r in res])),
                "median_nfev": float(np.median([r.nfev for r in res])),
                "median_time_us": times[label],
            }
        )
    rows.append(
        {
            "computation": "network guess alone",
            "inputs": len(q),
            "median_nit": 0.0,
            "median_nfev": 0.0,
            "median_time_us": times["network guess alone"],
        }
    )
    tab = pd.DataFrame(rows)
    ref = tab.set_index("computation").loc["Broyden from home"]
    tab["time_ratio_to_broyden_from_home"] = tab["median_time_us"] / ref["median_time_us"]
    tab["iteration_ratio_to_broyden_from_home"] = tab["median_nit"] / ref["median_nit"]
    notes = (
        f"{len(q)} random reachable inputs of the benchmark box, each solved once by every computation per "
        f"round ({cfg['repeats']} rounds), the computations taking turns on every input so that the load of a "
        "shared machine falls on all alike; medians of single calls (µs, this machine). Iterations and "
        "function evaluations are machine-independent; the time ratios are of computations timed in the same "
        "run. The hybrid taken apart: the network's guess alone, and the guess followed by Broyden stopped like "
        f"the hybrid's refinement (step below eps = {eps:g} m) without the hybrid's reachability check of the "
        "strokes."
    )
    return write_table(
        tab,
        outdir / "extra_hybrid_speed",
        title="The hybrid against quasi-Newton, per solve",
        notes=notes,
    )


# ---------------------------------------------------------------------------------- report
def network_accuracy_claims(
    accuracy: pd.DataFrame | None,
    log: pd.DataFrame | None,
    conv: pd.DataFrame,
    curves: pd.DataFrame,
    ref,
) -> list[Claim]:
    """§1.1's "1e-4 level" judged on the restarts of extra_bp_convergence (``conv``, per region;
    ``curves``: each run's curve, its returned network flagged ``best``): on our workspace box (an
    independent computation) and on the paper's working poses (Table 1's box: the region is assumed,
    the paper does not state it). Each claim asks whether the level lies in the range of its runs
    (half a decade, the reference CSV's tolerance; the paper reports one training). Where neither
    does, the reason says what was ruled out: the epoch limit (our box trained to convergence by the
    rule fixed before the runs, docs/zhao2017_3p4s.md#s4.5; ``log``: the pipeline's own training,
    row 0 of extra_bp_accuracy, ``accuracy``) and what was not shown (the region). Table 2's E_3
    measure is reported, not judged: it was looked at after the runs."""
    printed = printed_value(ref, "text_s1.1", "network_accuracy")
    c = conv.set_index("region")
    best = curves[curves["best"].astype(bool)]
    paper = c[c["role"] == "the paper's working poses"].iloc[0]
    runs = {
        name: best[best["region"] == name]["test_rms_m"].to_numpy() for name in (OURS, paper.name)
    }
    limit, e3 = _accuracy_context(accuracy, log, c.loc[OURS], paper)
    span = lambda v: f"{v.min():.1e} to {v.max():.1e} m"  # noqa: E731
    band = lambda v: int(np.sum(np.abs(np.log10(v / float(printed))) <= 0.5))  # noqa: E731
    unconverged = [n for n in runs if c.loc[n, "converged_runs"] < c.loc[n, "restarts"]]
    capped = f"; runs that hit the epoch cap in {', '.join(unconverged)}" if unconverged else ""
    ours_runs, paper_runs = runs[OURS], runs[paper.name]
    if band(ours_runs):
        text = (
            f"{band(ours_runs)} of {len(ours_runs)} trainings on our box within half a decade of "
            f"the level ({span(ours_runs)}){capped}"
        )
        reason = {OURS: text, paper.name: text}
    elif band(paper_runs):
        reason = {
            OURS: f"none of the {len(ours_runs)} trainings on our box reaches the level "
            f"({span(ours_runs)}; the epoch limit ruled out: {limit}trained to convergence); on "
            f"Table 1's box, the region assumed for the paper, {band(paper_runs)} of "
            f"{len(paper_runs)} do (that row){capped}. {e3}",
            paper.name: f"{band(paper_runs)} of {len(paper_runs)} trainings within half a decade "
            f"of the level ({span(paper_runs)}); on our box none ({span(ours_runs)}){capped}",
        }
    else:
        text = (
            f"cause unknown. Ruled out: the epoch limit on our box ({limit}trained to convergence "
            f"{len(ours_runs)} times: {span(ours_runs)}). Not shown: the paper's working poses as "
            f"region (Table 1's box, converged by the rule: {span(paper_runs)}). {e3}{capped}"
        )
        reason = {OURS: text, paper.name: text}
    # our box is the declared reading (issue 45): the region of the pipeline's network, chosen
    # before the convergence study; Table 1's box is an assumed region that tests the cause, so
    # where only it reaches the level, it shows the cause of ours differing
    shown = f"{KEY}/extra_bp_convergence.md" if band(paper_runs) and not band(ours_runs) else ""
    return [
        Claim.from_runs(
            KEY,
            "text_s1.1",
            "network_accuracy",
            printed,
            runs[name],
            "m",
            f"test-set RMS error on {where}, trained to convergence",
            what="trainings",
            basis=basis,
            reason=reason[name],
            declared=declared,
            evidence=evidence,
        )
        for name, where, basis, declared, evidence in (
            (
                OURS,
                "our workspace box",
                "",
                "the region of the pipeline's own network (the benchmark box), chosen before this "
                "study; the paper does not state its region",
                shown,
            ),
            (
                paper.name,
                "Table 1's box",
                "the sampling region: the box of Table 1's poses (the paper does not state it)",
                "",
                "",
            ),
        )
    ]


def _accuracy_context(
    accuracy: pd.DataFrame | None, log: pd.DataFrame | None, ours: pd.Series, paper: pd.Series
) -> tuple[str, str]:
    """The two sentences :func:`network_accuracy_claims` gives where the level is not reached: what
    ruled out the epoch limit (the pipeline's own training, ``log``, converged by the declared rule
    of ``ours``, our box's row of extra_bp_convergence) and Table 2's E_3 measure, reported only."""
    rule = (int(ours["window"]), float(ours["min_improvement"]))
    e = None if log is None else plateau_epoch(log["val_rms_m"], *rule)
    limit = (
        f"by the declared rule ({rule[1]:.0%} over {rule[0]} epochs) the pipeline's own training "
        f"had converged at epoch {e}, the rest improving its validation error by "
        f"{1 - log['val_rms_m'].min() / log['val_rms_m'][: e + 1].min():.0%}; "
        if e is not None
        else ""
    )
    e3 = (
        "Not tested: the error measure (seen after the runs): Table 2's E_3 gives "
        + (
            f"{float(accuracy.iloc[0].get('test_e3_m', np.nan)):.1e} m for the pipeline's network, "
            if accuracy is not None
            else ""
        )
        + f"{paper['test_e3_median_m']:.1e} m (median) on Table 1's box and "
        f"{ours['test_e3_median_m']:.1e} m converged on our box"
    )
    return limit, e3


def hybrid_speed_claims(t: pd.DataFrame, ref: pd.DataFrame) -> list[Claim]:
    """Conclusion (1)'s "more efficient than quasi-Newton", judged from one run
    (extra_hybrid_speed): on iterations (machine-independent) and on the time per solve (a ratio of
    two computations timed in the same run), the latter in two readings: the hybrid as the library
    runs it (its reachability check of the strokes included) and like for like (the network's guess,
    then Broyden stopped by the same rule, without the check). Taking the hybrid apart shows the cause
    of both: the first is far below 1 through its check and call overhead; in the second the guess
    costs about as much as the Broyden iterations it saves (a few µs each), so that ratio sits near 1
    and on which side depends on the machine (CI found it below 1 on one BLAS kernel and thread count
    and above on another: tests/test_stability.py). Both readings carry that decomposition as their
    evidence, and the weakest decides (:func:`parakin.claims.decide`)."""
    h, b = t.loc["hybrid (network + Broyden)"], t.loc["Broyden from home"]
    parts, guess = t.loc[GUESS_THEN_BROYDEN], t.loc["network guess alone"]
    evidence = f"{KEY}/extra_hybrid_speed.md"
    measured = (
        f"measured in one run: the hybrid {h['median_time_us']:.0f} µs per solve "
        f"({h['median_nit']:g} iterations), Broyden from home {b['median_time_us']:.0f} µs "
        f"({b['median_nit']:g} iterations), the network's guess alone {guess['median_time_us']:.0f} µs, "
        f"guess + Broyden without the hybrid's reachability check {parts['median_time_us']:.0f} µs "
        f"({parts['median_nit']:g} iterations)"
    )
    # the time the guess saves the Broyden call: Broyden from home against the call after the guess
    saved = b["median_time_us"] - (parts["median_time_us"] - guess["median_time_us"])
    quantity = "hybrid.time_ratio_vs_quasi_newton"
    printed = printed_value(ref, "conclusion", quantity)

    def time_reading(ratio: float, meaning: str, reason: str) -> Claim:
        """One reading of the time ratio (both carry the same evidence)."""
        return Claim(
            KEY, "conclusion", quantity, printed, float(ratio), "1", meaning, reason=reason,
            evidence=evidence,
        )  # fmt: skip

    return [
        Claim(
            KEY,
            "conclusion",
            "hybrid.iteration_ratio_vs_quasi_newton",
            printed_value(ref, "conclusion", "hybrid.iteration_ratio_vs_quasi_newton"),
            float(b["median_nit"] / h["median_nit"]),
            "1",
            f"median iterations per solve: Broyden from home {b['median_nit']:g} / hybrid "
            f"{h['median_nit']:g} (same run as the time per solve)",
            reason="iteration counts (machine-independent): the network's guess saves quasi-Newton "
            "iterations; on time per solve the claim does not survive (hybrid.time_ratio_vs_quasi_newton)",
            evidence=evidence,
        ),
        time_reading(
            b["median_time_us"] / h["median_time_us"],
            "median time per solve, Broyden from home / the hybrid as run (its reachability check "
            "included), timed in turns in one run",
            f"{measured}: most of the hybrid's time is its reachability check and call "
            "overhead, which the like-for-like reading leaves out",
        ),
        time_reading(
            b["median_time_us"] / parts["median_time_us"],
            "like for like: median time per solve, Broyden from home / the network's guess then "
            "Broyden (no reachability check), timed in turns in one run",
            f"{measured}: the saved iterations are worth about as much as the guess (they "
            f"save about {saved:.0f} µs of the Broyden call, the guess costs "
            f"{guess['median_time_us']:.0f} µs), so the ratio sits near 1 and on which side depends "
            "on the machine; the paper does not give its implementation's costs",
        ),
    ]


def failure_claims(t: pd.DataFrame, ref: pd.DataFrame) -> list[Claim]:
    """Conclusion (1)'s "quasi-Newton is strongly affected by the initial value" judged on
    extra_qn_failures: each quasi-Newton variant (:data:`QN_READINGS`: Broyden and three BFGS) on
    each region of :data:`QN_REGIONS` is one reading of the encoded bound (>= 0.1 % of reachable
    inputs fail from home). The paper names neither the variant nor the region, so no reading is
    declared and the weakest decides (:func:`parakin.claims.decide`); the height bands of the whole
    workspace stay in the artefact. A reading that meets no bound differs with its cause shown
    where another reading fails (the region or the variant, named in its reason)."""
    quantity = "quasi_newton.failure_rate_from_home"
    qn = t[t["solver"].isin(QN_READINGS) & t["region"].isin(QN_REGIONS)]
    printed = printed_value(ref, "conclusion", quantity)
    worst = qn.loc[qn["failure_rate"].idxmax()] if len(qn) else None
    out = []
    for solver in QN_READINGS:
        for region in QN_REGIONS:
            row = qn[(qn["solver"] == solver) & (qn["region"] == region)]
            if not len(row):
                continue
            r = row.iloc[0]
            here = qn[qn["region"] == region]
            others = "; ".join(
                f"{o.solver}: {o.failures}/{o.poses}"
                for o in here.itertuples()
                if o.solver != solver
            )
            meets = r.failure_rate >= float(printed)
            cause = (
                ""
                if meets or worst is None or worst.failure_rate < float(printed)
                else f"; from home every such input converges to its own pose here, while "
                f"{worst.solver} on {worst.region} fails on {worst.failure_rate:.1%}: the rate depends "
                "on the region and on the variant, neither of which the paper gives"
            )
            out.append(
                Claim(
                    KEY,
                    "conclusion",
                    quantity,
                    printed,
                    float(r.failure_rate),
                    "1",
                    f"{solver}, {region}",
                    reason=f"{r.failures}/{r.poses} fail ({r.not_converged} not converged, "
                    f"{r.another_assembly} on another assembly), 95 % CI [{r.rate_ci_low:.2g}, "
                    f"{r.rate_ci_high:.2g}]; the other variants here: {others}{cause}",
                    evidence=f"{KEY}/extra_qn_failures.md" if meets or cause else "",
                )
            )
    return out


def claims(figdir: Path, ref: pd.DataFrame) -> list[Claim]:
    out: list[Claim] = []
    t2 = figdir / "table2.csv"
    if t2.exists():
        tab = pd.read_csv(t2)
        for r in tab.itertuples():
            out.append(
                Claim(
                    KEY,
                    "table2",
                    f"case{r.case}.e3",
                    printed_value(ref, "table2", f"case{r.case}.e3"),
                    r.e3,
                    "m",
                    "hybrid (Broyden), E_3 of the iterate the paper's rule stops at",
                    reason="the printed E_3 is the error of the paper's stopped iterate, which depends on "
                    "where its (unprinted) solver stood when its step fell below eps (table2_iterates: ours "
                    "goes from the guess's error to round-off within the last steps); comparable is the "
                    "accuracy the stopping rule reaches: a bound, ours at most the printed E_3",
                )
            )
            out.append(
                Claim(
                    KEY,
                    "table2",
                    f"case{r.case}.iterations",
                    printed_value(ref, "table2", f"case{r.case}.iterations"),
                    r.iterations,
                    "1",
                    "hybrid (Broyden)",
                    reason="iteration counts within one (a step at the threshold)",
                )
            )
            for ax in "xyz":
                q = f"case{r.case}.solved.{ax}_p"
                out.append(
                    Claim(
                        KEY,
                        "table2",
                        q,
                        printed_value(ref, "table2", q),
                        float(getattr(r, f"solved_{ax}")),
                        "m",
                        "hybrid (Broyden)",
                        evidence=f"{KEY}/table2.md",
                        reason="tolerance = the paper's eps 1e-7: a solve stopped there fixes the position to "
                        "about eps; a larger difference contradicts the row's own printed E_3 (see the "
                        "reference note)",
                    )
                )
        time_reason = (
            "shown for information only: the median single-solve time on this machine, under "
            "whatever load it had (Table 2's time_ms); no verdict rests on a wall-clock time"
        )
        headline = (
            ("fk_accuracy", tab["e3"].max(), "m", "max E_3 over Table 2", ""),
            ("fk_iterations", tab["iterations"].max(), "1", "max over Table 2", ""),
            (
                "fk_time_max",
                tab["time_ms"].max(),
                "ms",
                "max median single-solve time, this machine",
                time_reason,
            ),
        )
        for art in ("text_s1.1", "abstract"):
            for quantity, value, unit, variant, reason in headline:
                out.append(
                    Claim(
                        KEY,
                        art,
                        quantity,
                        printed_value(ref, art, quantity),
                        float(value),
                        unit,
                        variant,
                        reason=reason,
                    )
                )
    conv, curves = figdir / "extra_bp_convergence.csv", figdir / "extra_bp_convergence_curves.csv"
    if conv.exists() and curves.exists():
        acc, log = figdir / "extra_bp_accuracy.csv", figdir / "extra_bp_training.csv"
        out += network_accuracy_claims(
            pd.read_csv(acc) if acc.exists() else None,
            pd.read_csv(log) if log.exists() else None,
            pd.read_csv(conv),
            pd.read_csv(curves),
            ref,
        )
    speed = figdir / "extra_hybrid_speed.csv"
    if speed.exists():
        out += hybrid_speed_claims(pd.read_csv(speed).set_index("computation"), ref)
    fails = figdir / "extra_qn_failures.csv"
    if fails.exists():
        out += failure_claims(pd.read_csv(fails), ref)
    return out


def _hybrid_paragraph(tab: pd.DataFrame, accuracy: pd.DataFrame, ref: pd.DataFrame) -> str:
    """Table 2: the network's accuracy and the hybrid FK's iterations and time against the paper's."""
    a = accuracy.iloc[0]
    smallest = accuracy.iloc[-1]
    e3 = [float(printed_value(ref, "table2", f"case{k}.e3")) for k in range(1, 6)]
    return (
        f"**Table 2 (hybrid FK).** Our 3-10-3 network, trained by Levenberg–Marquardt on {int(a['samples'])} IK "
        f"samples over the whole workspace box, predicts the platform position with a test-set RMS error of "
        f"{a['test_rms_m']:.2e} m (max {a['test_max_m']:.2e} m), "
        f"{a['test_rms_m'] / float(printed_value(ref, 'text_s1.1', 'network_accuracy')):.0f}× the paper's "
        f"'{printed_value(ref, 'text_s1.1', 'network_accuracy')} level', which depends on a sampling region the paper "
        f"does not state: the same training on the box {smallest['box']!r} gives {smallest['test_rms_m']:.1e} m "
        "(`extra_bp_accuracy.md`). Broyden's quasi-Newton method from that "
        f"guess, stopped at the paper's eps = {printed_value(ref, 'text_s1.1', 'epsilon')}, gives E_3 between "
        f"{tab['e3'].min():.1e} and {tab['e3'].max():.1e} m in {int(tab['iterations'].min())}–"
        f"{int(tab['iterations'].max())} iterations and {tab['time_ms'].min():.2f}–{tab['time_ms'].max():.2f} ms per "
        f"solve on this machine (paper: E_3 {min(e3):.2e}–{max(e3):.2e} m, "
        f"{printed_value(ref, 'text_s1.1', 'fk_iterations')} iterations, "
        f"< {printed_value(ref, 'text_s1.1', 'fk_time_max')} ms). Rows 2 and 4 of the printed table are internally "
        "inconsistent (see the notes of the reference CSV)."
    )


def _convergence_paragraph(convergence: pd.DataFrame, ref: pd.DataFrame) -> str:
    """The network's accuracy when trained to convergence, per sampling region."""
    c = convergence.set_index("region")
    row = lambda role: c[c["role"] == role].iloc[0]  # noqa: E731
    ours, paper = row("ours (the pipeline's network)"), row("the paper's working poses")
    return (
        f"**Network accuracy trained to convergence.** With a convergence rule fixed before the runs "
        f"(best validation error not {ours['min_improvement']:.0%} better over {int(ours['window'])} "
        f"epochs), {int(c['converged_runs'].sum())} of {int(c['restarts'].sum())} trainings converged; "
        f"median test RMS error {ours['test_rms_median_m']:.1e} m on our box, "
        f"{paper['test_rms_median_m']:.1e} m on Table 1's box, "
        f"{c['test_rms_median_m'].min():.1e} m on the smallest, against the paper's "
        f"'{printed_value(ref, 'text_s1.1', 'network_accuracy')} level' "
        "(`zhao2017_3p4s/extra_bp_convergence.md`; the cause is judged in the table above)."
    )


def _benchmark_paragraph(b: pd.DataFrame) -> str:
    """The FK solvers' single-solve latency and batched throughput."""
    h = b[b["method"] == "hybrid"].iloc[0]
    c = b[b["method"] == "closed-form"].iloc[0]
    r = b[b["method"] == "scipy-root"].iloc[0]
    return (
        f"**FK benchmark (ours).** Median single solve: hybrid {h['median_latency_us']:.0f} µs "
        f"({h['speedup_vs_paper_20ms']:.0f}× under the paper's 20 ms), closed form {c['median_latency_us']:.0f} µs, "
        f"scipy.optimize.root {r['median_latency_us']:.0f} µs. Batched throughput: hybrid "
        f"{h['throughput_per_s']:.3g}/s, closed form {c['throughput_per_s']:.3g}/s, against {r['throughput_per_s']:.3g}/s "
        "for a loop over scipy.optimize.root (`zhao2017_3p4s/fk_benchmark.md`)."
    )


def summary(figdir: Path, ref: pd.DataFrame) -> str:
    return table_text(
        figdir,
        {
            ("table2.csv", "extra_bp_accuracy.csv"): lambda t, a: _hybrid_paragraph(t, a, ref),
            "extra_bp_convergence.csv": lambda c: _convergence_paragraph(c, ref),
            "fk_benchmark.csv": _benchmark_paragraph,
        },
    )
