"""The BP (back-propagation) network of Zhao et al. 2017 (§1.1, Fig. 3) and its Levenberg-Marquardt
training, in the spirit of MATLAB's ``feedforwardnet(10)`` + ``trainlm``.

The paper gives the architecture (3 inputs = strokes l1..l3, one hidden layer of 10 neurons,
3 outputs = platform position) and the training algorithm (Levenberg-Marquardt, offline); it leaves
out the activations, the data scaling, the initialisation, the split and the stopping rules
(docs/zhao2017_3p4s.md#s3.1). We take MATLAB's defaults, since the paper used MATLAB:

* inputs and targets scaled column-wise to [-1, 1] by ``mapminmax`` (range taken over the whole
  data set before the split, as MATLAB's ``train`` does);
* hidden layer ``tansig`` (= tanh), output layer ``purelin`` (linear);
* Nguyen-Widrow initialisation of the hidden layer as MATLAB's ``initnw`` (row norms
  ``2 * 0.7 * hidden**(1/n_in)``, biases evenly spread over the same range with the sign of the
  first weight); output layer uniform on [-1, 1] (``initnw`` falls back to ``rands`` for purelin);
* random 70/15/15 train/validation/test split (``dividerand``), early stopping after ``max_fail``
  validation failures, ``mu`` = 1e-3 adapted by x0.1 / x10 up to 1e10, ``min_grad`` = 1e-7.

:class:`BPNetwork` is plain numpy (prediction sits on the ~100 us hybrid FK path); torch is needed
only by :func:`train_lm` and is imported there.
"""

from __future__ import annotations

import contextlib
import json
import math
import os
import time
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from parakin.errors import ShapeError
from parakin.io import atomic_writer

if TYPE_CHECKING:  # pragma: no cover
    import pandas as pd
    import torch

Array = NDArray[np.float64]

__all__ = [
    "BPNetwork",
    "train_lm",
    "torch_forward",
    "residuals",
    "residual_jacobian",
    "residual_jacobian_autograd",
    "nguyen_widrow_init",
    "plateau_epoch",
    "FORMAT_VERSION",
]

#: version tag written into every saved .npz; bump on an incompatible change of the layout
FORMAT_VERSION = 1
_ARRAYS = ("W1", "b1", "W2", "b2", "x_min", "x_max", "y_min", "y_max")
_DEFAULT_HINT = (
    "train a network with parakin.nn.train_lm(inputs, targets) and save it with "
    "BPNetwork.save(path), or run the pipeline (`snakemake --cores 2`), which writes it"
)


def _span(lo: Array, hi: Array) -> Array:
    """``hi - lo`` with zero spans (constant columns) replaced by 2, so they map to a constant."""
    s = hi - lo
    return np.where(s > 0, s, 2.0)


def _readonly(a: ArrayLike, shape: tuple[int, ...], name: str) -> Array:
    arr = np.array(a, dtype=np.float64, copy=True)
    if arr.shape != shape:
        raise ShapeError(f"{name} must have shape {shape}, got {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} contains non-finite values")
    arr.setflags(write=False)
    return arr


@dataclass(frozen=True, eq=False)
class BPNetwork:
    """A trained one-hidden-layer network ``n_in -> hidden (tanh) -> n_out (linear)``.

    ``y = denorm(W2 tanh(W1 norm(x) + b1) + b2)`` where ``norm`` maps ``[x_min, x_max]`` to
    ``[-1, 1]`` column-wise and ``denorm`` maps ``[-1, 1]`` back to ``[y_min, y_max]`` (MATLAB
    ``mapminmax``). All arrays are float64 and read-only.

    The network is fitted on the box ``[x_min, x_max]`` of its training inputs; outside it the
    output is an extrapolation (tanh saturates, the error grows quickly). No error is raised: the
    hybrid FK solver refines the guess anyway and judges convergence itself.

    ``meta`` holds JSON-serialisable facts about the training (seed, split, stop reason, test
    errors); it is saved and loaded with the weights.
    """

    W1: Array  #: (hidden, n_in) input -> hidden weights (normalised units)
    b1: Array  #: (hidden,)
    W2: Array  #: (n_out, hidden) hidden -> output weights
    b2: Array  #: (n_out,)
    x_min: Array  #: (n_in,) input range of the training data (mapminmax)
    x_max: Array  #: (n_in,)
    y_min: Array  #: (n_out,) target range of the training data
    y_max: Array  #: (n_out,)
    meta: Mapping[str, Any] = field(default_factory=dict)
    # the affine maps with the normalisation folded in: predict = tanh(x @ _A + _a) @ _B + _b
    _A: Array = field(init=False, repr=False)
    _a: Array = field(init=False, repr=False)
    _B: Array = field(init=False, repr=False)
    _b: Array = field(init=False, repr=False)

    def __post_init__(self) -> None:
        W1 = np.asarray(self.W1)
        if W1.ndim != 2:
            raise ShapeError(f"W1 must be a (hidden, n_in) matrix, got shape {W1.shape}")
        hidden, n_in = W1.shape
        W2 = np.asarray(self.W2)
        if W2.ndim != 2 or W2.shape[1] != hidden:
            raise ShapeError(f"W2 must be a (n_out, {hidden}) matrix, got shape {W2.shape}")
        n_out = W2.shape[0]
        shapes = {
            "W1": (hidden, n_in),
            "b1": (hidden,),
            "W2": (n_out, hidden),
            "b2": (n_out,),
            "x_min": (n_in,),
            "x_max": (n_in,),
            "y_min": (n_out,),
            "y_max": (n_out,),
        }
        for name, shape in shapes.items():
            object.__setattr__(self, name, _readonly(getattr(self, name), shape, name))
        for lo, hi in (("x_min", "x_max"), ("y_min", "y_max")):
            if np.any(getattr(self, lo) > getattr(self, hi)):
                raise ValueError(
                    f"{lo} = {getattr(self, lo)} must be <= {hi} = {getattr(self, hi)}"
                )
        object.__setattr__(self, "meta", dict(self.meta))
        # fold mapminmax into the two affine layers: x_n = gx * x + cx, y = gy * y_n + cy
        gx = 2.0 / _span(self.x_min, self.x_max)
        cx = -1.0 - gx * self.x_min
        gy = 0.5 * _span(self.y_min, self.y_max)
        cy = self.y_min + gy
        A = np.ascontiguousarray((self.W1 * gx).T)  # (n_in, hidden)
        a = self.W1 @ cx + self.b1
        B = np.ascontiguousarray((self.W2 * gy[:, None]).T)  # (hidden, n_out)
        b = gy * self.b2 + cy
        for name, value in (("_A", A), ("_a", a), ("_B", B), ("_b", b)):
            value.setflags(write=False)
            object.__setattr__(self, name, value)

    # ------------------------------------------------------------------ shape
    @property
    def n_in(self) -> int:
        return self.W1.shape[1]

    @property
    def hidden(self) -> int:
        return self.W1.shape[0]

    @property
    def n_out(self) -> int:
        return self.W2.shape[0]

    @property
    def n_weights(self) -> int:
        """Number of trainable parameters: 73 for 3-10-3."""
        return self.W1.size + self.b1.size + self.W2.size + self.b2.size

    # ------------------------------------------------------------------ evaluation
    def predict(self, inputs: ArrayLike) -> Array:
        """Network output for ``inputs`` of shape ``(..., n_in)`` -> ``(..., n_out)`` (SI units).

        Plain numpy, two small matmuls. Inputs outside ``[x_min, x_max]`` are extrapolated (see
        the class docstring). Only the trailing dimension is checked; non-finite inputs give
        non-finite outputs (the caller validates joint values).
        """
        x = np.asarray(inputs, dtype=np.float64)
        if x.ndim == 0 or x.shape[-1] != self._A.shape[0]:
            raise ShapeError(
                f"inputs must have {self._A.shape[0]} values along the last axis, got shape {x.shape}"
            )
        return np.tanh(x @ self._A + self._a) @ self._B + self._b

    __call__ = predict

    def normalise_inputs(self, inputs: ArrayLike) -> Array:
        """``mapminmax`` of ``inputs`` to the network's [-1, 1] input units."""
        x = np.asarray(inputs, dtype=np.float64)
        return 2.0 * (x - self.x_min) / _span(self.x_min, self.x_max) - 1.0

    def flat_weights(self) -> Array:
        """All weights as one vector in the order W1 (row-major), b1, W2 (row-major), b2."""
        return np.concatenate([self.W1.ravel(), self.b1, self.W2.ravel(), self.b2])

    # ------------------------------------------------------------------ persistence
    def save(self, path: str | os.PathLike) -> Path:
        """Write the network to ``path`` (.npz) atomically; returns the path."""
        arrays = {name: getattr(self, name) for name in _ARRAYS}
        meta = json.dumps(
            {
                "format_version": FORMAT_VERSION,
                "kind": "parakin.nn.BPNetwork",
                "hidden_activation": "tansig",
                "output_activation": "purelin",
                "meta": self.meta,
            },
            sort_keys=True,
        )

        def write(tmp: Path) -> None:
            with open(tmp, "wb") as fh:
                np.savez(fh, **arrays, header=np.array(meta))

        return atomic_writer(path, write)

    @classmethod
    def load(cls, path: str | os.PathLike, *, hint: str | None = None) -> BPNetwork:
        """Read a network written by :meth:`save`.

        Raises FileNotFoundError when ``path`` does not exist and ValueError when it is not a
        BPNetwork file; both messages name the path and how to create it (``hint`` overrides the
        default advice, e.g. with the exact CLI command of the pipeline).
        """
        path = Path(path)
        how = hint or _DEFAULT_HINT
        if not path.is_file():
            raise FileNotFoundError(
                f"BP network weights file {str(path)!r} does not exist; to create it, {how}"
            )
        try:
            with np.load(path, allow_pickle=False) as data:
                missing = [k for k in (*_ARRAYS, "header") if k not in data.files]
                if missing:
                    raise ValueError(f"missing arrays {missing}")
                header = json.loads(str(data["header"]))
                arrays = {k: data[k] for k in _ARRAYS}
            if header.get("kind") != "parakin.nn.BPNetwork":
                raise ValueError(
                    f"header kind {header.get('kind')!r} is not 'parakin.nn.BPNetwork'"
                )
            if header.get("format_version") != FORMAT_VERSION:
                raise ValueError(
                    f"format version {header.get('format_version')!r}, expected {FORMAT_VERSION}"
                )
            return cls(**arrays, meta=header.get("meta", {}))
        except (ValueError, OSError, KeyError, TypeError, json.JSONDecodeError, EOFError) as exc:
            # np.load raises OSError/ValueError/EOFError/BadZipFile(=Exception) on a corrupt file
            raise ValueError(
                f"{str(path)!r} is not a valid BP network weights file ({exc}); to recreate it, {how}"
            ) from exc
        except Exception as exc:  # zipfile.BadZipFile and friends
            raise ValueError(
                f"{str(path)!r} is not a valid BP network weights file ({type(exc).__name__}: {exc}); "
                f"to recreate it, {how}"
            ) from exc


# ====================================================================== torch side (training)
def _shapes(n_in: int, hidden: int, n_out: int) -> list[tuple[str, tuple[int, ...]]]:
    return [("W1", (hidden, n_in)), ("b1", (hidden,)), ("W2", (n_out, hidden)), ("b2", (n_out,))]


def _unflatten(w: torch.Tensor, n_in: int, hidden: int, n_out: int) -> dict[str, torch.Tensor]:
    out, i = {}, 0
    for name, shape in _shapes(n_in, hidden, n_out):
        k = math.prod(shape)
        out[name] = w[i : i + k].reshape(shape)
        i += k
    return out


def _net_normalised(
    w: torch.Tensor, x: torch.Tensor, n_in: int, hidden: int, n_out: int
) -> torch.Tensor:
    """The network in normalised units: ``W2 tanh(W1 x + b1) + b2`` with flat weights ``w``."""
    import torch

    p = _unflatten(w, n_in, hidden, n_out)
    return torch.tanh(x @ p["W1"].T + p["b1"]) @ p["W2"].T + p["b2"]


def residuals(w: torch.Tensor, x: torch.Tensor, t: torch.Tensor, hidden: int) -> torch.Tensor:
    """LM residual vector ``e = vec(net(x; w) - t)`` (normalised units), length ``N * n_out``.

    ``w`` is the flat weight vector (order of :meth:`BPNetwork.flat_weights`), ``x`` (N, n_in)
    and ``t`` (N, n_out) normalised inputs and targets.
    """
    return (_net_normalised(w, x, x.shape[-1], hidden, t.shape[-1]) - t).reshape(-1)


def residual_jacobian(
    w: torch.Tensor, x: torch.Tensor, t: torch.Tensor, hidden: int
) -> torch.Tensor:
    """``d residuals / d w``, shape ``(N * n_out, n_weights)``, rows in the order of :func:`residuals`.

    In closed form, for ``y = W2 tanh(W1 x + b1) + b2`` and ``h = tanh(W1 x + b1)``: output ``o``
    of sample ``n`` depends on ``W1[i, k]`` through ``W2[o, i] (1 - h_i^2) x_k``, on ``b1[i]``
    through ``W2[o, i] (1 - h_i^2)``, on ``W2[o, i]`` through ``h_i`` and on ``b2[o]`` with slope
    1; every other entry is zero. On 7,000 samples x 73 weights it takes a sixth of the time of
    reverse-mode automatic differentiation vectorised over the samples
    (:func:`residual_jacobian_autograd`), which it equals to rounding (a test holds them to 1e-15).
    """
    import torch

    n_in, n_out = x.shape[-1], t.shape[-1]
    p = _unflatten(w, n_in, hidden, n_out)
    h = torch.tanh(x @ p["W1"].T + p["b1"])  # (N, hidden)
    slope = p["W2"][None, :, :] * (1.0 - h * h)[:, None, :]  # (N, n_out, hidden): d y_o / d pre_i
    n = x.shape[0]
    d_w1 = (slope[:, :, :, None] * x[:, None, None, :]).reshape(n, n_out, hidden * n_in)
    d_w2 = torch.zeros(n, n_out, n_out, hidden, dtype=x.dtype)
    rows = torch.arange(n_out)
    d_w2[:, rows, rows, :] = h[:, None, :]
    d_b2 = torch.eye(n_out, dtype=x.dtype).expand(n, n_out, n_out)
    blocks = [d_w1, slope, d_w2.reshape(n, n_out, n_out * hidden), d_b2]
    return torch.cat(blocks, dim=2).reshape(n * n_out, w.numel())


def residual_jacobian_autograd(
    w: torch.Tensor, x: torch.Tensor, t: torch.Tensor, hidden: int
) -> torch.Tensor:
    """:func:`residual_jacobian` by ``torch.func``: reverse mode (``jacrev``, ``n_out`` VJPs) of the
    one-sample residual, vectorised over the samples with ``vmap``; the reference the closed form
    is tested against."""
    from torch.func import jacrev, vmap

    n_in, n_out = x.shape[-1], t.shape[-1]

    def one(w: torch.Tensor, xi: torch.Tensor, ti: torch.Tensor) -> torch.Tensor:
        return _net_normalised(w, xi, n_in, hidden, n_out) - ti

    return vmap(jacrev(one), in_dims=(None, 0, 0))(w, x, t).reshape(-1, w.numel())


def torch_forward(net: BPNetwork, inputs: torch.Tensor | ArrayLike) -> torch.Tensor:
    """The network evaluated in torch float64, normalisation NOT folded (the training graph).

    Reference for :meth:`BPNetwork.predict` (they agree to ~1e-15).
    """
    import torch

    x = torch.tensor(np.asarray(inputs, dtype=np.float64))
    t = lambda a: torch.tensor(a)  # noqa: E731 (copies: the network's arrays are read-only)
    xn = 2.0 * (x - t(net.x_min)) / t(_span(net.x_min, net.x_max)) - 1.0
    yn = _net_normalised(torch.as_tensor(net.flat_weights()), xn, net.n_in, net.hidden, net.n_out)
    return (yn + 1.0) * 0.5 * t(_span(net.y_min, net.y_max)) + t(net.y_min)


def nguyen_widrow_init(
    n_in: int, hidden: int, n_out: int, generator: torch.Generator
) -> torch.Tensor:
    """Initial flat weights as MATLAB ``initnw`` for a tansig hidden and a purelin output layer.

    Hidden layer (inputs already in [-1, 1], tansig active region [-2, 2]):
    rows of ``W1`` random directions of norm ``2 * 0.7 * hidden**(1/n_in)``, biases
    ``2 * 0.7 * hidden**(1/n_in) * linspace(-1, 1, hidden) * sign(W1[:, 0])``.
    Output layer: uniform on [-1, 1] (``rands``), as ``initnw`` does for purelin.
    """
    import torch

    mag = 0.7 * hidden ** (1.0 / n_in)
    d = 2.0 * torch.rand(hidden, n_in, generator=generator, dtype=torch.float64) - 1.0
    d = d / torch.linalg.vector_norm(d, dim=1, keepdim=True)
    W1 = 2.0 * mag * d
    spread = (
        torch.linspace(-1.0, 1.0, hidden, dtype=torch.float64)
        if hidden > 1
        else torch.zeros(1, dtype=torch.float64)
    )
    b1 = 2.0 * mag * spread * torch.sign(W1[:, 0])
    W2 = 2.0 * torch.rand(n_out, hidden, generator=generator, dtype=torch.float64) - 1.0
    b2 = 2.0 * torch.rand(n_out, generator=generator, dtype=torch.float64) - 1.0
    return torch.cat([W1.reshape(-1), b1, W2.reshape(-1), b2])


@contextlib.contextmanager
def _torch_session(seed: int, num_threads: int | None) -> Iterator[None]:
    """Deterministic algorithms, a fixed thread count and a forked global RNG seeded from
    ``seed``; all three restored on exit."""
    import torch

    prev_det = torch.are_deterministic_algorithms_enabled()
    prev_warn = torch.is_deterministic_algorithms_warn_only_enabled()
    prev_threads = torch.get_num_threads()
    try:
        torch.use_deterministic_algorithms(True)
        if num_threads is not None and num_threads != prev_threads:
            torch.set_num_threads(num_threads)
        with torch.random.fork_rng(devices=[]):
            torch.manual_seed(seed)
            yield
    finally:
        torch.use_deterministic_algorithms(prev_det, warn_only=prev_warn)
        if torch.get_num_threads() != prev_threads:
            torch.set_num_threads(prev_threads)


def _split(
    n: int, val_fraction: float, test_fraction: float, seed: int
) -> tuple[Array, Array, Array]:
    """Random train/val/test index sets (MATLAB ``dividerand``) from a numpy Generator."""
    perm = np.random.default_rng(seed).permutation(n)
    n_val = int(round(val_fraction * n))
    n_test = int(round(test_fraction * n))
    n_train = n - n_val - n_test
    if n_train < 1:
        raise ValueError(
            f"no training samples left: n = {n}, val_fraction = {val_fraction}, test_fraction = {test_fraction}"
        )
    return (
        np.sort(perm[:n_train]),
        np.sort(perm[n_train : n_train + n_val]),
        np.sort(perm[n_train + n_val :]),
    )


def _position_errors(pred: Array, target: Array) -> dict[str, float]:
    """RMS, max and 95th percentile of the Euclidean error ``|pred - target|`` per sample (SI),
    plus the largest and the mean absolute error of a single coordinate (the mean is Zhao 2017's
    ``E_3 = (|dx| + |dy| + |dz|) / 3`` averaged over the samples)."""
    if len(target) == 0:
        nan = float("nan")
        return {
            "rms_m": nan,
            "max_m": nan,
            "p95_m": nan,
            "max_abs_axis_m": nan,
            "mean_abs_axis_m": nan,
        }
    diff = pred - target
    norm = np.sqrt(np.einsum("ij,ij->i", diff, diff))
    return {
        "rms_m": float(np.sqrt(np.mean(norm**2))),
        "max_m": float(norm.max()),
        "p95_m": float(np.percentile(norm, 95)),
        "max_abs_axis_m": float(np.abs(diff).max()),
        "mean_abs_axis_m": float(np.abs(diff).mean()),
    }


def plateau_epoch(errors: ArrayLike, window: int, improvement: float = 0.01) -> int | None:
    """The first epoch at which :func:`train_lm`'s convergence rule (``plateau_window`` =
    ``window``, ``plateau_improvement`` = ``improvement``) fires on the per-epoch errors ``errors``
    (epoch 0 first): the best error so far is not ``improvement`` (relative) below the best error
    ``window`` epochs earlier. None if it never fires. Applies the rule to a finished log, e.g. one
    trained without it."""
    best = np.minimum.accumulate(np.asarray(errors, dtype=np.float64))
    k = np.arange(window, len(best))
    hit = best[k] > (1.0 - improvement) * best[k - window]
    return int(k[hit][0]) if hit.any() else None


_SETS = ("train", "val", "test")
_LOG_COLUMNS = (
    "epoch",
    "mu",
    "train_mse",
    "val_mse",
    "test_mse",
    "train_rms_m",
    "val_rms_m",
    "test_rms_m",
    "grad_norm",
)


@dataclass(frozen=True)
class _LMRules:
    """The damping and stopping rules of :func:`train_lm` (MATLAB ``trainlm``'s names)."""

    max_epochs: int
    mu_dec: float
    mu_inc: float
    mu_max: float
    max_fail: int
    min_grad: float
    goal: float
    plateau_window: int | None
    plateau_improvement: float

    def check(self, mu: float) -> None:
        """Raise ``ValueError`` naming the first rule out of its range (``mu`` = the initial mu)."""
        if not (mu > 0 and 0 < self.mu_dec < 1 < self.mu_inc and self.mu_max >= mu):
            raise ValueError(
                f"need mu > 0, 0 < mu_dec < 1 < mu_inc and mu_max >= mu; got mu = {mu}, "
                f"mu_dec = {self.mu_dec}, mu_inc = {self.mu_inc}, mu_max = {self.mu_max}"
            )
        if self.max_epochs < 0 or self.max_fail < 1:
            raise ValueError(
                f"max_epochs = {self.max_epochs} must be >= 0 and max_fail = {self.max_fail} >= 1"
            )
        window, improvement = self.plateau_window, self.plateau_improvement
        if window is not None and not (window >= 1 and 0 < improvement < 1):
            raise ValueError(
                f"plateau_window = {window} must be >= 1 and 0 < plateau_improvement = "
                f"{improvement} < 1"
            )

    def plateau(self, epoch: int, best_rms: list[float]) -> bool:
        """The rule of :func:`plateau_epoch`, applied as the log grows."""
        window = self.plateau_window
        return (
            window is not None
            and epoch >= window
            and best_rms[-1] > (1.0 - self.plateau_improvement) * best_rms[-1 - window]
        )

    def stop_reason(self, row: Mapping[str, float], val_fail: int, best_rms: list[float]) -> str:
        """Why training stops after the epoch logged in ``row`` ('' = go on); MATLAB trainlm order."""
        if row["train_mse"] <= self.goal:
            return "goal"
        if row["mu"] > self.mu_max:
            return "mu_max"
        if row["grad_norm"] < self.min_grad:
            return "min_grad"
        if val_fail >= self.max_fail:
            return "max_fail"
        if self.plateau(int(row["epoch"]), best_rms):
            return "plateau"
        if row["epoch"] >= self.max_epochs:
            return "max_epochs"
        return ""

    def summary(self) -> dict[str, Any]:
        """The rules as the summary reports them (plateau ones only when the rule is on, so the
        meta of a MATLAB-rules network is unchanged)."""
        out: dict[str, Any] = {
            "max_epochs": self.max_epochs,
            "max_fail": self.max_fail,
            "min_grad": self.min_grad,
            "goal": self.goal,
        }
        if self.plateau_window is not None:
            out.update(
                plateau_window=self.plateau_window, plateau_improvement=self.plateau_improvement
            )
        return out


def _training_arrays(inputs: ArrayLike, targets: ArrayLike) -> tuple[Array, Array]:
    """``inputs`` and ``targets`` as float arrays, checked: (N, n_in) and (N, n_out), finite."""
    X = np.asarray(inputs, dtype=np.float64)
    Y = np.asarray(targets, dtype=np.float64)
    if X.ndim != 2 or Y.ndim != 2 or len(X) != len(Y):
        raise ShapeError(
            f"inputs and targets must be (N, n_in) and (N, n_out) arrays, got {X.shape} and {Y.shape}"
        )
    for name, arr in (("inputs", X), ("targets", Y)):
        if not np.all(np.isfinite(arr)):
            raise ValueError(
                f"{name} contain non-finite values (first at {tuple(np.argwhere(~np.isfinite(arr))[0])})"
            )
    return X, Y


def _check_split_options(hidden: int, val_fraction: float, test_fraction: float) -> None:
    """Raise ``ValueError`` unless ``hidden`` >= 1 and the two fractions leave a training set."""
    if hidden < 1:
        raise ValueError(f"hidden = {hidden} must be >= 1")
    if not (0 <= val_fraction < 1 and 0 <= test_fraction < 1 and val_fraction + test_fraction < 1):
        raise ValueError(
            f"val_fraction = {val_fraction} and test_fraction = {test_fraction} must be >= 0 with sum < 1"
        )


def _minmax_normalise(X: Array, Y: Array) -> tuple[tuple[Array, ...], Array, Array, Array]:
    """MATLAB ``mapminmax`` over the whole data set: the bounds ``(x_min, x_max, y_min, y_max)``,
    the inputs and targets scaled to [-1, 1], and the metres per normalised unit of each output."""
    x_min, x_max, y_min, y_max = X.min(0), X.max(0), Y.min(0), Y.max(0)
    Xn = 2.0 * (X - x_min) / _span(x_min, x_max) - 1.0
    Yn = 2.0 * (Y - y_min) / _span(y_min, y_max) - 1.0
    y_scale = 0.5 * _span(y_min, y_max)  # metres per normalised unit, per output
    return (x_min, x_max, y_min, y_max), Xn, Yn, y_scale


def _tensor_sets(
    Xn: Array, Yn: Array, split: tuple[NDArray[np.intp], ...]
) -> dict[str, tuple[torch.Tensor, torch.Tensor]]:
    """The normalised (inputs, targets) of each set as tensors, keyed train/val/test."""
    import torch

    tt = lambda a: torch.from_numpy(np.ascontiguousarray(a))  # noqa: E731
    return {name: (tt(Xn[idx]), tt(Yn[idx])) for name, idx in zip(_SETS, split)}


def _network(
    w: torch.Tensor,
    shape: tuple[int, int, int],
    bounds: tuple[Array, ...],
    meta: Mapping[str, Any] | None = None,
) -> BPNetwork:
    """The :class:`BPNetwork` of the flat weight vector ``w``."""
    p = _unflatten(w, *shape)
    x_min, x_max, y_min, y_max = bounds
    return BPNetwork(
        **{k: v.numpy().copy() for k, v in p.items()},
        x_min=x_min,
        x_max=x_max,
        y_min=y_min,
        y_max=y_max,
        meta=meta or {},
    )


def _set_errors(
    w: torch.Tensor,
    data: tuple[torch.Tensor, torch.Tensor],
    shape: tuple[int, int, int],
    scale: torch.Tensor,
) -> tuple[float, float]:
    """(normalised MSE, RMS Euclidean error in SI units) of weights ``w`` on one set; NaN if empty."""
    import torch

    x, t = data
    if len(x) == 0:
        return float("nan"), float("nan")
    d = _net_normalised(w, x, *shape) - t
    mse = float(torch.mean(d * d))
    rms_m = float(torch.sqrt(torch.mean(torch.sum((d * scale) ** 2, dim=1))))
    return mse, rms_m


def _epoch_row(
    epoch: int,
    mu: float,
    w: torch.Tensor,
    e: torch.Tensor,
    sse: float,
    Jte: torch.Tensor,
    sets: Mapping[str, tuple[torch.Tensor, torch.Tensor]],
    shape: tuple[int, int, int],
    scale: torch.Tensor,
) -> dict[str, float]:
    """One row of :func:`train_lm`'s log: the errors of weights ``w`` on every set."""
    import torch

    m = sets["train"][1].numel()
    grad_norm = float(2.0 * torch.linalg.vector_norm(Jte) / m)
    train_mse, train_rms = (
        sse / m,
        float(torch.sqrt(torch.mean(torch.sum((e.reshape(-1, shape[2]) * scale) ** 2, 1)))),
    )
    val_mse, val_rms = _set_errors(w, sets["val"], shape, scale)
    test_mse, test_rms = _set_errors(w, sets["test"], shape, scale)
    return {
        "epoch": epoch,
        "mu": mu,
        "train_mse": train_mse,
        "val_mse": val_mse,
        "test_mse": test_mse,
        "train_rms_m": train_rms,
        "val_rms_m": val_rms,
        "test_rms_m": test_rms,
        "grad_norm": grad_norm,
    }


def _lm_step(
    w: torch.Tensor,
    e: torch.Tensor,
    sse: float,
    JtJ: torch.Tensor,
    Jte: torch.Tensor,
    mu: float,
    train: tuple[torch.Tensor, torch.Tensor],
    hidden: int,
    rules: _LMRules,
) -> tuple[torch.Tensor, torch.Tensor, float, float]:
    """One LM step: raise mu until the step lowers the training SSE. Returns the new
    ``(w, e, sse, mu)``, or the old ones with mu past ``mu_max`` if no step does."""
    import torch

    x_tr, t_tr = train
    eye = torch.eye(w.numel(), dtype=torch.float64)
    rhs = -Jte.unsqueeze(1)
    while mu <= rules.mu_max:
        L, info = torch.linalg.cholesky_ex(JtJ + mu * eye)
        if int(info) == 0:
            w_new = w + torch.cholesky_solve(rhs, L).squeeze(1)
            e_new = residuals(w_new, x_tr, t_tr, hidden)
            sse_new = float(e_new @ e_new)
            if sse_new < sse:
                return w_new, e_new, sse_new, max(mu * rules.mu_dec, 1e-20)
        mu *= rules.mu_inc
    return w, e, sse, mu


def _lm_epochs(
    sets: Mapping[str, tuple[torch.Tensor, torch.Tensor]],
    shape: tuple[int, int, int],
    y_scale: Array,
    seed: int,
    mu: float,
    rules: _LMRules,
    progress: Callable[[int, float, float], None] | None,
) -> tuple[list[dict[str, float]], torch.Tensor, int, int, str, float]:
    """:func:`train_lm`'s epochs from the Nguyen-Widrow weights of ``seed``. Returns (log rows,
    best weights, best epoch, last epoch, stop reason, final mu)."""
    import torch

    hidden = shape[1]
    train = sets["train"]
    has_val = len(sets["val"][0]) > 0
    scale = torch.from_numpy(np.ascontiguousarray(y_scale))
    w = nguyen_widrow_init(*shape, torch.Generator().manual_seed(seed))
    e = residuals(w, *train, hidden)
    sse = float(e @ e)
    best_w, best_val, best_epoch, val_fail = w.clone(), math.inf, 0, 0
    best_rms: list[float] = []  # best validation (or training) RMS error up to each epoch
    rows: list[dict[str, float]] = []
    epoch = 0
    while True:
        J = residual_jacobian(w, *train, hidden)
        JtJ = J.T @ J
        Jte = J.T @ e
        row = _epoch_row(epoch, mu, w, e, sse, Jte, sets, shape, scale)
        rows.append(row)
        if progress is not None:
            progress(epoch, row["train_mse"], row["val_mse"])
        # early-stopping bookkeeping (MATLAB: a failure is an epoch that does not beat the best)
        if not has_val:
            best_w, best_epoch = w, epoch
        elif row["val_mse"] < best_val:
            best_w, best_val, best_epoch, val_fail = w, row["val_mse"], epoch, 0
        elif epoch > 0:
            val_fail += 1
        watched = row["val_rms_m"] if has_val else row["train_rms_m"]
        best_rms.append(min(watched, best_rms[-1]) if best_rms else watched)
        stop_reason = rules.stop_reason(row, val_fail, best_rms)
        if stop_reason:
            return rows, best_w, best_epoch, epoch, stop_reason, mu
        w, e, sse, mu = _lm_step(w, e, sse, JtJ, Jte, mu, train, hidden, rules)
        epoch += 1


def _summary_head(
    run: tuple[list[dict[str, float]], torch.Tensor, int, int, str, float],
    split: tuple[NDArray[np.intp], ...],
    shape: tuple[int, int, int],
    n_weights: int,
    seed: int,
    rules: _LMRules,
) -> dict[str, Any]:
    """:func:`train_lm`'s summary up to the errors: the run (from :func:`_lm_epochs`), the set
    sizes, the network's shape and the rules."""
    _, _, best_epoch, epochs, stop_reason, mu_final = run
    return {
        "epochs": epochs,
        "stop_reason": stop_reason,
        "best_epoch": best_epoch,
        **{f"n_{name}": len(idx) for name, idx in zip(_SETS, split)},
        "n_in": shape[0],
        "hidden": shape[1],
        "n_out": shape[2],
        "n_weights": n_weights,
        "seed": seed,
        "init": "nguyen-widrow (MATLAB initnw)",
        "algorithm": "levenberg-marquardt (MATLAB trainlm)",
        "mu_final": mu_final,
        **rules.summary(),
    }


def _set_position_errors(
    net: BPNetwork, X: Array, Y: Array, split: tuple[NDArray[np.intp], ...]
) -> dict[str, float]:
    """:func:`_position_errors` of ``net`` on each set, keys prefixed with the set's name."""
    out: dict[str, float] = {}
    for name, idx in zip(_SETS, split):
        errs = (
            _position_errors(net.predict(X[idx]), Y[idx])
            if len(idx)
            else _position_errors(Y[:0], Y[:0])
        )
        out.update({f"{name}_{k}": v for k, v in errs.items()})
    return out


def train_lm(
    inputs: ArrayLike,
    targets: ArrayLike,
    *,
    hidden: int = 10,
    seed: int = 0,
    max_epochs: int = 1000,
    val_fraction: float = 0.15,
    test_fraction: float = 0.15,
    mu: float = 1e-3,
    mu_dec: float = 0.1,
    mu_inc: float = 10.0,
    mu_max: float = 1e10,
    max_fail: int = 6,
    min_grad: float = 1e-7,
    goal: float = 0.0,
    plateau_window: int | None = None,
    plateau_improvement: float = 0.01,
    progress: Callable[[int, float, float], None] | None = None,
    num_threads: int | None = 1,
) -> tuple[BPNetwork, pd.DataFrame, dict[str, Any]]:
    """Train a ``n_in -> hidden (tanh) -> n_out`` network by Levenberg-Marquardt (MATLAB ``trainlm``).

    ``inputs`` (N, n_in) and ``targets`` (N, n_out) in SI units (for the 3-P(4S) FK: strokes and
    platform positions, metres). Each epoch: the residual vector ``e`` over the normalised training
    set and its Jacobian ``J`` w.r.t. all weights (in closed form, :func:`residual_jacobian`); then, starting from the
    current ``mu``, solve ``(J^T J + mu I) d = -J^T e`` by Cholesky and accept the step if it lowers
    the training SSE (then ``mu *= mu_dec``), else ``mu *= mu_inc`` and retry while
    ``mu <= mu_max``. Only improving steps are accepted, so the training error never increases.

    Stops (checked at the start of each epoch, MATLAB order) when the training MSE ``<= goal``,
    ``mu > mu_max``, the gradient norm ``|2 J^T e / m|`` of the training MSE ``< min_grad``
    (``m`` = number of residuals), the validation MSE has not improved on its best for
    ``max_fail`` consecutive epochs (MATLAB's ``val_fail``), or after ``max_epochs``. With
    ``plateau_window`` = K (not MATLAB; off by default) it also stops, reason ``plateau``, once the
    best validation RMS position error has not improved by at least ``plateau_improvement``
    (relative, 0.01 = 1 %) over the last K epochs (the training error when there is no validation
    set): a convergence rule that can be fixed before a run. Returns the weights of the epoch with
    the best validation MSE (the last epoch when ``val_fraction`` is 0).

    Determinism: the split comes from ``numpy.random.default_rng(seed)``, the Nguyen-Widrow
    initialisation from a ``torch.Generator`` seeded with ``seed``; training runs in float64 with
    ``torch.use_deterministic_algorithms(True)``, the global torch RNG forked and seeded from
    ``seed``, and ``num_threads`` intra-op threads (default 1: bitwise reproducible whatever the
    machine's core count; ``None`` keeps the current setting). All torch global state is restored.

    Returns ``(network, log, summary)``. ``log`` has one row per epoch (row 0 = the initial
    weights): ``epoch``, ``mu`` (held after that epoch's step), ``train_mse``/``val_mse``/``test_mse``
    (normalised units, mean over all residuals), ``train_rms_m``/``val_rms_m``/``test_rms_m`` (RMS
    of the Euclidean error of the de-normalised outputs, SI units), ``grad_norm``. ``summary``:
    ``epochs``, ``stop_reason`` (``goal``, ``mu_max``, ``min_grad``, ``max_fail``, ``plateau``,
    ``max_epochs``),
    ``best_epoch``, and the errors of the returned network on each set (``test_rms_m``,
    ``test_max_m`` = max Euclidean error, ``test_p95_m``, ``test_max_abs_axis_m``,
    ``test_mean_abs_axis_m`` = mean absolute coordinate error, likewise for
    train and val), set sizes, hyper-parameters and ``wall_time_s``.
    """
    import pandas as pd

    X, Y = _training_arrays(inputs, targets)
    _check_split_options(hidden, val_fraction, test_fraction)
    rules = _LMRules(max_epochs, mu_dec, mu_inc, mu_max, max_fail, min_grad, goal,
                     plateau_window, plateau_improvement)  # fmt: skip
    rules.check(mu)

    start = time.perf_counter()
    shape = (X.shape[1], hidden, Y.shape[1])
    split = _split(len(X), val_fraction, test_fraction, seed)
    bounds, Xn, Yn, y_scale = _minmax_normalise(X, Y)
    with _torch_session(seed, num_threads):
        run = _lm_epochs(_tensor_sets(Xn, Yn, split), shape, y_scale, seed, mu, rules, progress)
    rows, best_w = run[0], run[1]

    log = pd.DataFrame(rows, columns=list(_LOG_COLUMNS))
    net = _network(best_w, shape, bounds)
    summary = _summary_head(run, split, shape, net.n_weights, seed, rules)
    summary.update(_set_position_errors(net, X, Y, split))
    summary["wall_time_s"] = time.perf_counter() - start
    net = _network(
        best_w, shape, bounds, meta={k: v for k, v in summary.items() if k != "wall_time_s"}
    )
    return net, log, summary
