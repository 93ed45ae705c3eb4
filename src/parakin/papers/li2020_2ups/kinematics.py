"""Li 2020 §1-§2: the mechanism (Fig. 1), concomitant motion (eqs 6-8, 14), the IK, and our extras:
the parasitic translations X, dZ the paper does not discuss, and the number of real FK solutions.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from parakin.claims import Claim, printed_value
from parakin.config import rng
from parakin.io import write_table
from parakin.papers.drawing import draw_skeleton_table
from parakin.papers.li2020_2ups.common import KEY, mech, table, table_and_figure
from parakin.papers.li2020_2ups.symbolic import derivation, loop_closure_model
from parakin.papers.sections import table_text
from parakin.registry import DESCRIPTIVE, EXACT, ROUNDING

#: pose drawn in Fig. 1 (deg, deg, mm): tilted so that both rotations are visible
FIG1_POSE = (15.0, 20.0, 30.0)
#: length of the frame arrows in Fig. 1 (m)
FIG1_FRAME_LENGTH = 0.06


def draw_fig01(frame: pd.DataFrame, path: Path) -> Path:
    """Fig. 1 drawn from its skeleton table (``fig01_mechanism.csv``) alone."""
    return draw_skeleton_table(
        frame,
        path,
        frame_length=FIG1_FRAME_LENGTH,
        title=f"2-UPS/(S+SPR)R at β = {FIG1_POSE[0]:g}°, γ = {FIG1_POSE[1]:g}°, Y = {FIG1_POSE[2]:g} mm",
    )


@table_and_figure("fig01", "fig01_mechanism", draw_fig01, config=[KEY], tolerance=DESCRIPTIVE)
def fig01(config: dict) -> pd.DataFrame:
    """Fig. 1 redrawn from our model at FIG1_POSE, with the plotted coordinates as CSV."""
    from parakin.plot import skeleton_table

    m = mech(config)
    pose = np.array([np.deg2rad(FIG1_POSE[0]), np.deg2rad(FIG1_POSE[1]), FIG1_POSE[2] * 1e-3])
    return skeleton_table(m.skeleton(pose), frame_length=FIG1_FRAME_LENGTH)


@table("concomitant", "extra_concomitant", config=[KEY], tolerance=ROUNDING)
def concomitant(config: dict, outdir: Path) -> list[Path]:
    """Symbolic derivation (sympy) that alpha = 0 and eq. (14) follow from (6), (12); the vector IK
    against the scalar closed forms; a numeric check with an independent loop-closure model."""
    cfg = config[KEY]
    d = derivation()
    m = mech(config)
    model = loop_closure_model(
        cfg["concomitant_samples"], rng(config, f"{KEY}.concomitant"), c=m.c, a=m.a
    )
    y = model["P"][:, 1]
    rho = np.sqrt(m.c**2 - y**2)
    rows = [
        ("B2B3 = R (B3' - B2') equals eq (7)", "symbolic", float(d["eq7_ok"]), "1 = true"),
        ("B2B3 . e_y", "symbolic", np.nan, str(d["constraint_y"])),
        (
            "solutions alpha in [0, 2pi) for cos(beta) != 0",
            "symbolic",
            np.nan,
            ", ".join(f"{v:.6g}" for v in d["alpha_solutions"]) + " (pi = flipped platform)",
        ),
        ("X from B2B3 . P = 0 at alpha = 0 (eq 8)", "symbolic", np.nan, str(d["X_of_Z"][0])),
        ("eq (14) satisfies (6) and (12)", "symbolic", float(d["P_ok"]), "1 = true"),
        ("|l1|^2 vector form = closed form", "symbolic", float(d["ik_ok"][0]), "1 = true"),
        ("|l2|^2 vector form = closed form", "symbolic", float(d["ik_ok"][1]), "1 = true"),
        ("|l3|^2 vector form = closed form", "symbolic", float(d["ik_ok"][2]), "1 = true"),
        (
            "printed (16)^2 - vector |l2|^2",
            "symbolic",
            float(d["printed16_differs"]),
            f"{d['printed16_minus_vector']} (nonzero: Y missing in the printed y term)",
        ),
        (
            "max |alpha| (rad), loop-closure model",
            "numeric",
            float(np.max(np.abs(model["alpha"]))),
            f"{len(y)} random assemblies",
        ),
        (
            "max |X - rho sin beta| (m)",
            "numeric",
            float(np.max(np.abs(model["P"][:, 0] - rho * np.sin(model["beta"])))),
            "",
        ),
        (
            "max |Z - rho cos beta| (m)",
            "numeric",
            float(np.max(np.abs(model["P"][:, 2] - rho * np.cos(model["beta"])))),
            "",
        ),
        (
            "constraint Jacobian rank (DOF = 6 - rank)",
            "numeric",
            float(_dof(config)),
            "DOF at random poses",
        ),
    ]
    df = pd.DataFrame(rows, columns=["check", "kind", "value", "detail"])
    return write_table(
        df,
        outdir / "extra_concomitant",
        title="Concomitant motion: symbolic and numeric checks",
        notes="alpha = 0 follows from the first constraint of (6) alone; X and Z are functions of (beta, Y).",
    )


def _dof(config: dict) -> int:
    """6 minus the rank of the Jacobian of constraints (6) + (12) in (alpha, beta, gamma, X, Y, Z) at
    random admissible poses (the minimum DOF found)."""
    m = mech(config)
    g = rng(config, f"{KEY}.dof")
    dofs = []
    for _ in range(20):
        beta, gamma, y = g.uniform(-0.5, 0.5), g.uniform(-1, 1), g.uniform(-0.02, 0.11)
        rho = np.sqrt(m.c**2 - y**2)
        z0 = np.array([0.0, beta, gamma, rho * np.sin(beta), y, rho * np.cos(beta)])

        def cons(z: np.ndarray) -> np.ndarray:
            al, be = z[0], z[1]
            b2b3 = (
                np.sqrt(2)
                * m.b
                * np.array([-np.cos(al) * np.cos(be), -np.sin(al) * np.cos(be), np.sin(be)])
            )
            return np.array([b2b3[1], b2b3 @ z[3:], z[3:] @ z[3:] - m.c**2])

        jac = np.stack([(cons(z0 + e) - cons(z0 - e)) / 2e-7 for e in 1e-7 * np.eye(6)], axis=-1)
        dofs.append(6 - np.linalg.matrix_rank(jac, tol=1e-8))
    return int(min(dofs))


def _grid(frame: pd.DataFrame, axes: tuple[str, ...], *values: str) -> list[np.ndarray]:
    """Columns of a grid saved raveled in ``indexing="ij"`` order, reshaped to the grid (one axis
    per name in ``axes``, as many points as it has distinct values): axes first, then ``values``."""
    shape = tuple(frame[a].nunique() for a in axes)
    return [frame[c].to_numpy().reshape(shape) for c in (*axes, *values)]


def draw_parasitic(frame: pd.DataFrame, path: Path) -> Path:
    """X and dZ over the (beta, Y) box, drawn from ``extra_parasitic.csv`` alone."""
    from matplotlib.ticker import MaxNLocator

    from parakin.plot import new_figure, save_figure

    bb, yy, x_mm, dz_mm = _grid(frame, ("beta_deg", "Y_mm"), "X_mm", "dZ_mm")
    a, b, c = (float(frame[k].iloc[0]) for k in ("a_mm", "b_mm", "c_mm"))
    fig, axes = new_figure((6.6, 2.8))
    fig.clear()
    fig.set_layout_engine(None)
    axs = fig.subplots(1, 2)
    fig.subplots_adjust(left=0.09, right=0.92, bottom=0.17, top=0.86, wspace=0.62)
    for ax, val, lab in zip(axs, (x_mm, dz_mm), ("X (mm)", "ΔZ = c − Z (mm)")):
        cs = ax.contourf(bb, yy, val, levels=15, cmap="viridis")
        ax.contour(bb, yy, val, levels=cs.levels[::3], colors="k", linewidths=0.4)
        fig.colorbar(cs, ax=ax, label=lab)
        ax.set_xlabel("β (deg)")
        ax.set_ylabel("Y (mm)")
        ax.set_xticks([-30, -15, 0, 15, 30])
        # no tick at the lower y limit: its label would touch the x axis's first one at the corner
        ax.yaxis.set_major_locator(
            MaxNLocator(nbins="auto", steps=[1, 2, 2.5, 5, 10], prune="lower")
        )
    fig.suptitle(f"Parasitic translations of B1 (a, b, c = {a:g}, {b:g}, {c:g} mm)")
    return save_figure(fig, path)


@table_and_figure("parasitic", "extra_parasitic", draw_parasitic, config=[KEY], tolerance=ROUNDING)
def parasitic(config: dict) -> pd.DataFrame:
    """Extra: the parasitic translations X = rho sin(beta) and dZ = c - rho cos(beta) over the
    Table 1 box (beta, Y); gamma does not enter."""
    m = mech(config)
    n = config[KEY]["grid"]
    lo, hi = m.pose_bounds()
    beta = np.linspace(lo[0], hi[0], n)
    y = np.linspace(lo[2], hi[2], n)
    bb, yy = np.meshgrid(beta, y, indexing="ij")
    p = m.position(np.stack([bb, np.zeros_like(bb), yy], axis=-1))
    x_mm, dz_mm = p[..., 0] * 1e3, (m.c - p[..., 2]) * 1e3
    df = pd.DataFrame(
        {
            "beta_deg": np.rad2deg(bb).ravel(),
            "Y_mm": (yy * 1e3).ravel(),
            "X_mm": x_mm.ravel(),
            "dZ_mm": dz_mm.ravel(),
            # the geometry, for the figure's title
            "a_mm": m.a * 1e3,
            "b_mm": m.b * 1e3,
            "c_mm": m.c * 1e3,
        }
    )
    return df


def draw_fk_solutions(frame: pd.DataFrame, path: Path) -> Path:
    """Real FK solutions over (beta, gamma) at three Y, drawn from ``extra_fk_solutions.csv`` alone."""
    from parakin.plot import new_figure, save_figure

    bb, gg, yy, count = _grid(frame, ("beta_deg", "gamma_deg", "Y_mm"), "n_real")
    fig, _ = new_figure((7.2, 2.6))
    fig.clear()
    axs = fig.subplots(1, 3, sharey=True)
    levels = np.arange(-0.5, 9.5, 1.0)
    for i, ax in enumerate(axs):
        cs = ax.contourf(bb[..., i], gg[..., i], count[..., i], levels=levels, cmap="Blues")
        ax.set_title(f"Y = {yy[0, 0, i]:g} mm", fontsize="small")
        ax.set_xlabel("β (deg)")
    axs[0].set_ylabel("γ (deg)")
    fig.colorbar(cs, ax=axs, label="real FK solutions", ticks=range(0, 9))
    return save_figure(fig, path)


def _pose_grid(config: dict) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """The (beta, gamma) grid of Table 1's box at three Y (low, middle, high): the poses
    ``(n, n, 3, 3)`` and their columns ``beta_deg``, ``gamma_deg``, ``Y_mm``."""
    n = config[KEY]["grid"]
    lo, hi = mech(config).pose_bounds()
    ys = np.array([lo[2], 0.5 * (lo[2] + hi[2]), hi[2]])
    bb, gg, yy = np.meshgrid(
        np.linspace(lo[0], hi[0], n), np.linspace(lo[1], hi[1], n), ys, indexing="ij"
    )
    columns = {
        "beta_deg": np.rad2deg(bb).ravel(),
        "gamma_deg": np.rad2deg(gg).ravel(),
        "Y_mm": (yy * 1e3).ravel(),
    }
    return np.stack([bb, gg, yy], axis=-1), columns


@table_and_figure(
    "fk_solutions", "extra_fk_solutions", draw_fk_solutions, config=[KEY], tolerance=EXACT
)
def solution_count(config: dict) -> pd.DataFrame:
    """Extra: number of real FK solutions (rho > 0 branch, all of beta, gamma) of the strokes of each
    pose of a (beta, gamma) grid, at three Y across Table 1's range; and how many lie in the box."""
    m = mech(config)
    lo, hi = m.pose_bounds()
    poses, grid = _pose_grid(config)
    sols = m.fk_all(m.ik(poses))
    real = np.all(np.isfinite(sols), axis=-1)
    with np.errstate(invalid="ignore"):
        inbox = real & np.all((sols >= lo - 1e-9) & (sols <= hi + 1e-9), axis=-1)
    return pd.DataFrame({**grid, "n_real": real.sum(-1).ravel(), "n_in_box": inbox.sum(-1).ravel()})


def draw_singularity_workspace(frame: pd.DataFrame, path: Path) -> Path:
    """det J over (beta, gamma) at three Y, hatched where eq. (19) fails, drawn from
    ``extra_singularity_workspace.csv`` alone."""
    from parakin.plot import new_figure, save_figure, use_style

    bb, gg, yy, det, inside = _grid(
        frame, ("beta_deg", "gamma_deg", "Y_mm"), "det_J_m2", "within_eq19"
    )
    inside = inside.astype(bool)
    with use_style():
        fig, _ = new_figure((7.2, 2.8))
        fig.clear()
        axs = fig.subplots(1, 3, sharey=True)
        crosses = bool(det.min() < 0 < det.max())
        levels = (
            (np.linspace(-1, 1, 17) * np.abs(det).max())
            if crosses
            else np.linspace(det.min(), det.max(), 13)
        )
        for i, ax in enumerate(axs):
            cs = ax.contourf(
                bb[..., i],
                gg[..., i],
                det[..., i],
                levels=levels,
                cmap="RdBu_r" if crosses else "viridis",
            )
            ax.contour(
                bb[..., i], gg[..., i], det[..., i], levels=[0.0], colors="k", linewidths=1.2
            )
            ax.contourf(
                bb[..., i],
                gg[..., i],
                (~inside[..., i]).astype(float),
                levels=[0.5, 1.5],
                colors="none",
                hatches=["////"],
            )
            ax.set_title(f"Y = {yy[0, 0, i]:g} mm", fontsize="small")
            ax.set_xlabel("β (deg)")
        axs[0].set_ylabel("γ (deg)")
        fig.colorbar(cs, ax=axs, label="det J (m²)", format="%.1e")
        fig.suptitle(
            "Velocity Jacobian over Table 1's search box; hatched: strokes beyond eq. (19)"
            + ("; black: det J = 0" if crosses else "; det J never vanishes here"),
            fontsize="small",
        )
    return save_figure(fig, path)


@table_and_figure(
    "singularity_workspace",
    "extra_singularity_workspace",
    draw_singularity_workspace,
    config=[KEY],
    tolerance=EXACT,
)
def singularity_workspace(config: dict) -> pd.DataFrame:
    """Extra: det of the velocity Jacobian J (qdot = J posedot) over (beta, gamma) at three Y of
    Table 1's box, with the region where eq (19)'s stroke limits hold; cond(J) beside it.
    det J = 0 is a singularity (the pose cannot be held by the actuators)."""
    m = mech(config)
    poses, grid = _pose_grid(config)
    jac = m.velocity_jacobian(poses)
    return pd.DataFrame(
        {
            **grid,
            "det_J_m2": np.linalg.det(jac).ravel(),
            "cond_J": np.linalg.cond(jac).ravel(),
            "within_eq19": m.within_limits(m.ik(poses)).ravel(),
        }
    )


def claims(figdir: Path, ref: pd.DataFrame) -> list[Claim]:
    out: list[Claim] = []
    path = figdir / "extra_concomitant.csv"
    if path.exists():
        df = pd.read_csv(path).set_index("check")
        rank_dof = float(df.loc["constraint Jacobian rank (DOF = 6 - rank)", "value"])
        out.append(
            Claim(
                KEY,
                "text_s1.1",
                "dof",
                printed_value(ref, "text_s1.1", "dof"),
                rank_dof,
                "1",
                variant="6 - rank of the constraint Jacobian of (6)+(12)",
            )
        )
        alpha = float(df.loc["max |alpha| (rad), loop-closure model", "value"])
        out.append(
            Claim(
                KEY,
                "eq8",
                "alpha",
                printed_value(ref, "eq8", "alpha"),
                float(np.rad2deg(alpha)),
                "deg",
                variant="max |alpha| over random assemblies of an independent loop-closure model",
                reason="also symbolic: B2B3.e_y = -sqrt2 b sin(alpha) cos(beta) = 0 gives alpha = 0 "
                "(pi = flipped platform); but X = rho sin(beta), Z = rho cos(beta) are parasitic translations",
            )
        )
        out += _equation_claims(df, ref)
    return out


#: how the "as printed" equation claims (docs/li2020_2ups.md#s6, claims C2, C4, C5) are encoded as numbers
TRUE = "1"  #: a symbolic identity checked by sympy: 1 = holds, 0 = fails
ZERO = "0"  #: a numeric residual that the printed equation implies to be 0


def _equation_claims(df: pd.DataFrame, ref: pd.DataFrame) -> list[Claim]:
    """Claims C2, C4, C5 of docs/li2020_2ups.md#s6: eqs (1), (5), (7), (14), (9)-(11), (15)-(17) as printed, read from
    extra_concomitant.csv (sympy identities encoded 1 = holds, numeric residuals encoded as 0)."""
    enc = "encoding: printed 1 = the paper's equation; ours 1 = sympy proves the identity, 0 = it fails"
    v = df["value"]

    def check(
        artefact: str,
        quantity: str,
        name: str,
        unit: str,
        variant: str,
        reason: str,
        scale: float = 1.0,
    ) -> Claim:
        """The claim ``artefact.quantity`` that the check ``name`` of extra_concomitant decides."""
        ours = float(v[name]) * scale
        return Claim(
            KEY,
            artefact,
            quantity,
            printed_value(ref, artefact, quantity),
            ours,
            unit,
            variant=variant,
            reason=reason,
        )

    out = [
        check(
            "eq7",
            "B2B3_identity",
            "B2B3 = R (B3' - B2') equals eq (7)",
            "1",
            "sympy: R(alpha, beta, gamma) (eq 1) applied to B3' - B2' (eq 5) minus eq (7)",
            enc + " (the extracted 'S_beta' is read as sin(beta))",
        ),
        check(
            "eq14",
            "P_identity",
            "eq (14) satisfies (6) and (12)",
            "1",
            "sympy: P = (sin b sqrt(c^2 - Y^2), Y, cos b sqrt(c^2 - Y^2)) satisfies (6) and (12)",
            enc,
        ),
    ]
    out += [
        check(
            "eq14",
            f"{x}_residual",
            f"max |{x} - rho {trig} beta| (m)",
            "mm",
            f"max |{x} - {trig}(b) sqrt(c^2 - Y^2)| over an independent loop-closure model",
            "numeric residual of eq (14), tolerance 1e-9 mm (round-off)",
            scale=1e3,
        )
        for x, trig in (("X", "sin"), ("Z", "cos"))
    ]
    out += [
        check(
            "eq9-11",
            f"l{j}_identity",
            f"|l{j}|^2 vector form = closed form",
            "1",
            f"sympy: |l{j}|^2 of the vector form (eqs 9-11, 14) = our scalar closed form",
            enc,
        )
        for j in (1, 2, 3)
    ]
    diff = df.loc["printed (16)^2 - vector |l2|^2"]
    out.append(
        Claim(
            KEY,
            "eq16",
            "printed_equals_vector_form",
            printed_value(ref, "eq16", "printed_equals_vector_form"),
            1.0 - float(diff["value"]),
            "1",
            variant="sympy: printed scalar (16)^2 - vector |l2|^2 (1 = identical)",
            evidence=f"{KEY}/extra_concomitant.md",
            reason=f"typo in the printed (16): the difference is {diff['detail']}; we code (9)-(11) + (14), "
            "which the paper's own vector derivation gives",
        )
    )
    return out


def _workspace_sentence(d: pd.DataFrame) -> str:
    """Eq. (19)'s stroke limits and the sign of det J over Table 1's search box."""
    sign_change = bool((d["det_J_m2"] > 0).any() and (d["det_J_m2"] < 0).any())
    return (
        f"**Singularities and workspace (ours).** Over Table 1's search box, eq. (19)'s stroke limits hold on "
        f"{d['within_eq19'].mean():.0%} of the (beta, gamma, Y) grid; det J "
        f"{'changes sign (a singularity crosses the box)' if sign_change else 'keeps its sign (no singularity in the box)'}"
        f", max cond(J) = {d['cond_J'].max():.3g} (`extra_singularity_workspace.png`)."
    )


def _concomitant_sentence(df: pd.DataFrame) -> str:
    """What sympy and the loop-closure model say of the concomitant motion and of eq. (16), from
    the checks indexed by name."""
    ok = all(df.loc[k, "value"] == 1.0 for k in df.index if "closed form" in k or "eq (7)" in k)
    return (
        "Concomitant motion: sympy confirms eq (7) and that the first constraint of (6) reads "
        f"`{df.loc['B2B3 . e_y', 'detail']} = 0`, so α = 0 (α = π is the flipped platform); an independent "
        f"loop-closure model gives max |α| = {df.loc['max |alpha| (rad), loop-closure model', 'value']:.2g} rad. "
        f"The vector IK (9)-(11) equals our scalar closed forms symbolically: {'yes' if ok else 'NO'}; the printed (16) "
        f"differs from it by `{df.loc['printed (16)^2 - vector |l2|^2', 'detail'].split(' (')[0]}` (Y missing)."
    )


def _fk_solutions_sentence(df: pd.DataFrame) -> str:
    """How many real FK solutions the poses of the box grid have."""
    counts = df["n_real"].value_counts().sort_index()
    return (
        "Real FK solutions (ρ > 0 branch) over the box grid: "
        + ", ".join(f"{int(k)}: {int(v)} poses" for k, v in counts.items())
        + f"; solutions inside the Table 1 box: min {df['n_in_box'].min()}, max {df['n_in_box'].max()}."
    )


def summary(figdir: Path, ref: pd.DataFrame) -> str:
    return table_text(
        figdir,
        {
            "extra_singularity_workspace.csv": _workspace_sentence,
            "extra_concomitant.csv": lambda c: _concomitant_sentence(c.set_index("check")),
            "extra_parasitic.csv": lambda df: (
                f"Parasitic translations over the Table 1 box: |X| up to {df['X_mm'].abs().max():.1f} mm, "
                f"ΔZ up to {df['dZ_mm'].max():.1f} mm — 'no concomitant motion' holds only for the rotation about z."
            ),
            "extra_fk_solutions.csv": _fk_solutions_sentence,
        },
    )
