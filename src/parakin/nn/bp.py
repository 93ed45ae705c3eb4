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

    Built with ``torch.func``: reverse mode (``jacrev``, ``n_out`` VJPs) of the one-sample
    residual, vectorised over the samples with ``vmap``. On 7,000 samples x 73 weights this takes
    ~19 ms on one core, 8x faster than forward mode over the whole residual vector
    (``jacfwd(residuals)``, 73 JVPs of the full batch); both agree to 1e-16.
    """
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
    set and its Jacobian ``J`` w.r.t. all weights (``torch.func.jacfwd``); then, starting from the
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
    import torch

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
    if hidden < 1:
        raise ValueError(f"hidden = {hidden} must be >= 1")
    if not (0 <= val_fraction < 1 and 0 <= test_fraction < 1 and val_fraction + test_fraction < 1):
        raise ValueError(
            f"val_fraction = {val_fraction} and test_fraction = {test_fraction} must be >= 0 with sum < 1"
        )
    if not (mu > 0 and 0 < mu_dec < 1 < mu_inc and mu_max >= mu):
        raise ValueError(
            f"need mu > 0, 0 < mu_dec < 1 < mu_inc and mu_max >= mu; got mu = {mu}, "
            f"mu_dec = {mu_dec}, mu_inc = {mu_inc}, mu_max = {mu_max}"
        )
    if max_epochs < 0 or max_fail < 1:
        raise ValueError(f"max_epochs = {max_epochs} must be >= 0 and max_fail = {max_fail} >= 1")
    if plateau_window is not None and not (plateau_window >= 1 and 0 < plateau_improvement < 1):
        raise ValueError(
            f"plateau_window = {plateau_window} must be >= 1 and 0 < plateau_improvement = "
            f"{plateau_improvement} < 1"
        )

    start = time.perf_counter()
    n_in, n_out = X.shape[1], Y.shape[1]
    itr, iva, ite = _split(len(X), val_fraction, test_fraction, seed)
    x_min, x_max, y_min, y_max = X.min(0), X.max(0), Y.min(0), Y.max(0)
    Xn = 2.0 * (X - x_min) / _span(x_min, x_max) - 1.0
    Yn = 2.0 * (Y - y_min) / _span(y_min, y_max) - 1.0
    y_scale = 0.5 * _span(y_min, y_max)  # metres per normalised unit, per output

    def make_net(w: torch.Tensor, meta: Mapping[str, Any] | None = None) -> BPNetwork:
        p = _unflatten(w, n_in, hidden, n_out)
        return BPNetwork(
            **{k: v.numpy().copy() for k, v in p.items()},
            x_min=x_min,
            x_max=x_max,
            y_min=y_min,
            y_max=y_max,
            meta=meta or {},
        )

    rows: list[dict[str, float]] = []
    with _torch_session(seed, num_threads):
        tt = lambda a: torch.from_numpy(np.ascontiguousarray(a))  # noqa: E731
        sets = {
            name: (tt(Xn[idx]), tt(Yn[idx]))
            for name, idx in (("train", itr), ("val", iva), ("test", ite))
        }
        x_tr, t_tr = sets["train"]
        m = t_tr.numel()
        scale = tt(y_scale)
        gen = torch.Generator().manual_seed(seed)
        w = nguyen_widrow_init(n_in, hidden, n_out, gen)
        eye = torch.eye(w.numel(), dtype=torch.float64)

        def evaluate(w: torch.Tensor, name: str) -> tuple[float, float]:
            x, t = sets[name]
            if len(x) == 0:
                return float("nan"), float("nan")
            d = _net_normalised(w, x, n_in, hidden, n_out) - t
            mse = float(torch.mean(d * d))
            rms_m = float(torch.sqrt(torch.mean(torch.sum((d * scale) ** 2, dim=1))))
            return mse, rms_m

        e = residuals(w, x_tr, t_tr, hidden)
        sse = float(e @ e)
        best_w, best_val, best_epoch, val_fail = w.clone(), math.inf, 0, 0
        best_rms: list[float] = []  # best validation (or training) RMS error up to each epoch
        epoch, stop_reason = 0, "max_epochs"
        while True:
            J = residual_jacobian(w, x_tr, t_tr, hidden)
            JtJ = J.T @ J
            Jte = J.T @ e
            grad_norm = float(2.0 * torch.linalg.vector_norm(Jte) / m)
            train_mse, train_rms = (
                sse / m,
                float(torch.sqrt(torch.mean(torch.sum((e.reshape(-1, n_out) * scale) ** 2, 1)))),
            )
            val_mse, val_rms = evaluate(w, "val")
            test_mse, test_rms = evaluate(w, "test")
            rows.append(
                {
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
            )
            if progress is not None:
                progress(epoch, train_mse, val_mse)
            # early-stopping bookkeeping (MATLAB: a failure is an epoch that does not beat the best)
            if len(iva) == 0:
                best_w, best_epoch = w, epoch
            elif val_mse < best_val:
                best_w, best_val, best_epoch, val_fail = w, val_mse, epoch, 0
            elif epoch > 0:
                val_fail += 1
            watched = val_rms if len(iva) else train_rms
            best_rms.append(min(watched, best_rms[-1]) if best_rms else watched)
            plateau = (  # the rule of plateau_epoch, applied as the log grows
                plateau_window is not None
                and epoch >= plateau_window
                and best_rms[-1] > (1.0 - plateau_improvement) * best_rms[-1 - plateau_window]
            )
            # stopping criteria, MATLAB trainlm order
            if train_mse <= goal:
                stop_reason = "goal"
            elif mu > mu_max:
                stop_reason = "mu_max"
            elif grad_norm < min_grad:
                stop_reason = "min_grad"
            elif val_fail >= max_fail:
                stop_reason = "max_fail"
            elif plateau:
                stop_reason = "plateau"
            elif epoch >= max_epochs:
                stop_reason = "max_epochs"
            else:
                stop_reason = ""
            if stop_reason:
                break
            # one LM step: raise mu until the step lowers the training SSE
            rhs = -Jte.unsqueeze(1)
            while mu <= mu_max:
                L, info = torch.linalg.cholesky_ex(JtJ + mu * eye)
                if int(info) == 0:
                    w_new = w + torch.cholesky_solve(rhs, L).squeeze(1)
                    e_new = residuals(w_new, x_tr, t_tr, hidden)
                    sse_new = float(e_new @ e_new)
                    if sse_new < sse:
                        w, e, sse = w_new, e_new, sse_new
                        mu = max(mu * mu_dec, 1e-20)
                        break
                mu *= mu_inc
            epoch += 1

    log = pd.DataFrame(
        rows,
        columns=[
            "epoch",
            "mu",
            "train_mse",
            "val_mse",
            "test_mse",
            "train_rms_m",
            "val_rms_m",
            "test_rms_m",
            "grad_norm",
        ],
    )
    net = make_net(best_w)
    summary: dict[str, Any] = {
        "epochs": epoch,
        "stop_reason": stop_reason,
        "best_epoch": best_epoch,
        "n_train": len(itr),
        "n_val": len(iva),
        "n_test": len(ite),
        "n_in": n_in,
        "hidden": hidden,
        "n_out": n_out,
        "n_weights": net.n_weights,
        "seed": seed,
        "init": "nguyen-widrow (MATLAB initnw)",
        "algorithm": "levenberg-marquardt (MATLAB trainlm)",
        "mu_final": mu,
        "max_epochs": max_epochs,
        "max_fail": max_fail,
        "min_grad": min_grad,
        "goal": goal,
    }
    if plateau_window is not None:  # only then: the meta of a MATLAB-rules network is unchanged
        summary.update(plateau_window=plateau_window, plateau_improvement=plateau_improvement)
    for name, idx in (("train", itr), ("val", iva), ("test", ite)):
        errs = (
            _position_errors(net.predict(X[idx]), Y[idx])
            if len(idx)
            else _position_errors(Y[:0], Y[:0])
        )
        summary.update({f"{name}_{k}": v for k, v in errs.items()})
    summary["wall_time_s"] = time.perf_counter() - start
    net = make_net(best_w, meta={k: v for k, v in summary.items() if k != "wall_time_s"})
    return net, log, summary
