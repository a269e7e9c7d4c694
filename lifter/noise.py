"""The 2D detection error model (PoseLifter §4.2, spec §7): a per-joint Gaussian + uniform mixture.

Model
-----
For each of the 17 H36M joints ``j`` the 2D detection error ``e = detection - ground truth`` (px) is

    p(e) = gamma_j * N(e; mu_j, diag(sigma_j^2)) + (1 - gamma_j) / v,      v = 100 x 100 px^2 (fixed)

i.e. an inlier Gaussian plus an outlier component that is uniform over a 100 x 100 px box around the
true joint (its density ``1/v`` is used as a constant, as in the paper). It is fitted by EM
(:func:`fit_mixture`), initialised from the single-Gaussian maximum-likelihood fit
(:func:`fit_gaussian`, mean and standard deviation per axis) with ``gamma = 0.9``, and iterated until the
mean log-likelihood improves by less than ``tol`` (nats per sample) or ``max_iter`` is reached. EM never
decreases the likelihood. The single Gaussian ``N(mu, diag sigma^2)`` is kept as the baseline (Table 3,
"single Gaussian" row). NLLs are mean negative log-likelihoods in nats per 2D error (density in px^-2).

Units and the scale rule
------------------------
Errors are in **image pixels** of a person of the **reference 2D scale** ``sigma_ref`` (px): the median
of the fitted samples' 2D scale ``sigma`` (:func:`lifter.normalization.pose_scale`, the paper's RMS
radius of the ground-truth 2D pose). A detector works on a person-sized crop, so its error in image
pixels grows with the person's size. Hence, when fitting, every error is first rescaled to the reference
size, ``e * sigma_ref / sigma_i``; when sampling for a pose of scale ``sigma`` every noise component (the
Gaussian mean and spread, and the outlier box) is multiplied by ``s = sigma / sigma_ref``. This is the
paper's convention (noise defined in 256-px crop units, so image-px noise grows with the crop) and it is
what keeps the noise sensible for people much larger or smaller than H36M's. Within H36M's narrow range
it is not visible in the data: by quintile of the training GT scale (68, 83, 95, 108, 126 px) the median
raw error is 9.2, 7.4, 7.2, 8.0, 9.3 px (U-shaped; small scales are mostly distant and crouched or
seated poses, which are harder), so the rule is a modelling assumption, not a measured law.

The shipped fit (``assets/error_model/sh_mixture.json``, ``poselifter fit-noise``): Stacked-Hourglass
detections of S1, S5, S6, S7, S8 (every 5th frame, 4 cameras, 293,116 per joint) converted with
:func:`lifter.keypoints.convert`, minus the distorted GT projection; reference scale 95.5 px. Mean
gamma 0.905 (wrists 0.79, shoulders 0.97); inlier sigma 3.8-9.2 px (mean 5.8 x, 5.5 y); single-Gaussian
sigma 6.4-21 px (mean 12.4 x, 12.8 y); mean NLL 6.77 (mixture) vs 7.78 (Gaussian) nats; 8-16 EM
iterations to tol 1e-7. Every joint has mu_x of about +2 px (a detector/pixel-convention offset).

Sampling and the ``level`` knob
-------------------------------
:meth:`ErrorModel.sample` draws, per joint independently, a Bernoulli "outlier" with probability
``p_out = min((1 - gamma_j) * level, max(0.5, 1 - gamma_j))`` and then adds

* inliers: ``s * level * (mu_j + sigma_j * n)``, ``n ~ N(0, I_2)``;
* outliers: ``s * u``, ``u ~ U[-50, 50]^2`` px (the v box around the true joint), or nothing at all when
  ``outliers=False`` (the authors' code, which never samples the uniform component).

So ``level = 0`` returns the input unchanged, ``level = 1`` samples the fitted model, and ``level > 1``
exaggerates it (wider, more biased inliers and proportionally more outliers, capped at 50 %).
The outlier box does not grow with ``level``. :meth:`ErrorModel.sample_torch` is the sampler (torch, any
device, used by training); :meth:`ErrorModel.sample` is its numpy front end.

Fitting the model to H36M's real detections (data loading, the converter report, the figures) is
:mod:`lifter.noise_fit`; this module knows nothing of the dataset or the API.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, overload

import numpy as np
import torch
from numpy.typing import ArrayLike
from tqdm.auto import tqdm

from . import resources as assets
from ._array import ArrayT
from ._checks import PoseLifterError, as_points, warn_user
from .normalization import pose_scale
from .skeleton import JOINT_NAMES, NUM_JOINTS

OUTLIER_BOX_PX: float = 100.0
"""Side (px, at the reference scale) of the square outlier box centred on the true joint."""
OUTLIER_VOLUME_PX2: float = OUTLIER_BOX_PX**2
"""``v`` in the mixture, px^2."""
INIT_GAMMA: float = 0.9
MAX_OUTLIER_PROB: float = 0.5
DEFAULT_ASSET_NAME: str = "sh_mixture.json"
FORMAT_TAG: str = "poselifter-error-model"
FORMAT_VERSION: int = 1

STANDIN_SIGMA_PX: float = 8.0
STANDIN_REFERENCE_SCALE_PX: float = 100.0
"""The stand-in used when no fitted model is shipped: a zero-mean Gaussian with 8 px per axis for a
person of 2D scale 100 px, gamma = 1 (no outliers)."""

_LOG_2PI = math.log(2.0 * math.pi)


# ------------------------------------------------------------------------------------------------
# Fitting
# ------------------------------------------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class MixtureFit:
    """EM result for one joint. ``mu``, ``sigma``: ``(2,)`` px; ``nll``: nats per sample;
    ``history``: mean log-likelihood after the initialisation and after every EM iteration."""

    gamma: float
    mu: np.ndarray
    sigma: np.ndarray
    nll: float
    iterations: int
    converged: bool
    history: tuple[float, ...]


def _check_errors(errors: ArrayLike) -> np.ndarray:
    e = np.asarray(errors, np.float64)
    if e.ndim != 2 or e.shape[1] != 2 or e.shape[0] < 2:
        raise PoseLifterError(f"errors: expected shape (N >= 2, 2) px, got {tuple(e.shape)}")
    if not np.all(np.isfinite(e)):
        raise PoseLifterError("errors: contains NaN/inf values")
    return e


def gaussian_loglik(errors: np.ndarray, mu: np.ndarray, sigma: np.ndarray) -> np.ndarray:
    """Per-sample log-density ``(N,)`` of ``N(mu, diag sigma^2)`` at errors ``(N, 2)`` px (log px^-2)."""
    z = (errors - mu) / sigma
    return -0.5 * (z**2).sum(-1) - np.log(sigma).sum() - _LOG_2PI


def fit_gaussian(errors: ArrayLike) -> tuple[np.ndarray, np.ndarray, float]:
    """Single-Gaussian ML fit of errors ``(N, 2)`` px: ``mu (2,)``, ``sigma (2,)`` (std about the mean,
    ddof 0) and the mean NLL (nats). The authors' code uses the RMS about zero instead (spec §7)."""
    e = _check_errors(errors)
    mu = e.mean(0)
    sigma = np.maximum(e.std(0), 1e-6)
    return mu, sigma, float(-gaussian_loglik(e, mu, sigma).mean())


def mixture_loglik(errors: np.ndarray, gamma: float, mu: np.ndarray, sigma: np.ndarray, *,
                   v: float = OUTLIER_VOLUME_PX2) -> np.ndarray:
    """Per-sample log-density ``(N,)`` of ``gamma N(mu, diag sigma^2) + (1 - gamma)/v``."""
    lg = np.log(max(gamma, 1e-300)) + gaussian_loglik(errors, mu, sigma)
    lo = np.log(max(1.0 - gamma, 1e-300)) - np.log(v)
    return np.logaddexp(lg, lo)


def check_em_settings(tol: float, max_iter: int) -> None:
    """Refuse EM settings that are no fit: ``tol`` (nats/sample) must be a number >= 0 (0: every iteration up to
    ``max_iter``) and ``max_iter`` >= 1 (a researcher trial: --tol -1 was taken, and --max-iter 0 wrote the
    initialisation as a fit)."""
    if not (isinstance(tol, (int, float)) and math.isfinite(tol) and tol >= 0):
        raise PoseLifterError(f"EM tol (--tol) must be a number >= 0 (nats per sample; default 1e-7; 0 runs every "
                              f"iteration up to --max-iter), got {tol!r}")
    if isinstance(max_iter, bool) or not isinstance(max_iter, int) or max_iter < 1:
        raise PoseLifterError(f"EM max_iter (--max-iter) must be an integer >= 1 (default 1000), got {max_iter!r}")


def fit_mixture(
    errors: ArrayLike,
    *,
    v: float = OUTLIER_VOLUME_PX2,
    init_gamma: float = INIT_GAMMA,
    tol: float = 1e-7,
    max_iter: int = 1000,
    min_sigma: float = 1e-3,
) -> MixtureFit:
    """EM for ``gamma N(mu, diag sigma^2) + (1 - gamma)/v`` on errors ``(N, 2)`` px (v fixed, px^2).

    Initialised from :func:`fit_gaussian` with ``gamma = init_gamma``; stops when the mean
    log-likelihood improves by less than ``tol`` nats per sample, or after ``max_iter`` iterations.
    """
    check_em_settings(tol, max_iter)
    e = _check_errors(errors)
    mu, sigma, _ = fit_gaussian(e)
    gamma = float(init_gamma)
    ll = float(mixture_loglik(e, gamma, mu, sigma, v=v).mean())
    history = [ll]
    converged = False
    it = 0
    for it in range(1, max_iter + 1):  # noqa: B007 - `it` is the iteration count reported after the loop
        # E-step: responsibilities of the Gaussian
        lg = np.log(gamma) + gaussian_loglik(e, mu, sigma)
        lo = np.log(max(1.0 - gamma, 1e-300)) - np.log(v)
        r = np.exp(lg - np.logaddexp(lg, lo))
        # M-step
        rs = r.sum()
        if rs <= 1e-9:
            raise PoseLifterError("EM collapsed: no inliers left (all errors explained by the uniform component)")
        gamma = float(np.clip(rs / len(e), 1e-9, 1.0 - 1e-12))
        mu = (r[:, None] * e).sum(0) / rs
        sigma = np.maximum(np.sqrt((r[:, None] * (e - mu) ** 2).sum(0) / rs), min_sigma)
        new_ll = float(mixture_loglik(e, gamma, mu, sigma, v=v).mean())
        history.append(new_ll)
        improvement = new_ll - ll
        ll = new_ll
        if improvement < tol:
            converged = True
            break
    return MixtureFit(gamma=gamma, mu=mu, sigma=sigma, nll=-ll, iterations=it, converged=converged,
                      history=tuple(history))


# ------------------------------------------------------------------------------------------------
# The model
# ------------------------------------------------------------------------------------------------


def _arr(x: Any, shape: tuple[int, ...], name: str) -> np.ndarray:
    a = np.array(x, np.float64)  # a private copy, made read-only below (the dataclass is frozen)
    if a.shape != shape:
        raise PoseLifterError(f"{name}: expected shape {shape}, got {a.shape}")
    if not np.all(np.isfinite(a)):
        raise PoseLifterError(f"{name}: contains NaN/inf values")
    a.setflags(write=False)
    return a


def shipped_error_models() -> list[str]:
    """Names of the shipped error-model fits (``error_model/*.json`` of :mod:`lifter.resources`)."""
    node = assets.asset("error_model")
    return sorted(p.name[:-5] for p in node.iterdir() if p.name.endswith(".json")) if node.is_dir() else []


@overload
def outlier_probability(gamma: ArrayLike, level: torch.Tensor) -> torch.Tensor: ...
@overload
def outlier_probability(gamma: ArrayLike, level: float | np.ndarray) -> np.ndarray: ...
def outlier_probability(gamma: ArrayLike, level: float | np.ndarray | torch.Tensor) -> np.ndarray | torch.Tensor:
    """``p_out = min((1 - gamma) * level, max(0.5, 1 - gamma))`` per joint (module docstring); numpy or torch,
    ``gamma`` ``(17,)`` broadcast against ``level``."""
    if isinstance(level, torch.Tensor):
        q = 1.0 - torch.as_tensor(np.array(gamma), dtype=level.dtype, device=level.device)
        return torch.minimum(q * level, torch.clamp(q, min=MAX_OUTLIER_PROB))
    q = 1.0 - np.asarray(gamma, np.float64)
    return np.minimum(q * np.asarray(level, np.float64), np.maximum(MAX_OUTLIER_PROB, q))


@dataclass(frozen=True, eq=False)
class ErrorModel:
    """Per-joint 2D error model, all in image px at the reference 2D scale ``reference_scale``.

    gamma: ``(17,)`` inlier weight; mu, sigma: ``(17, 2)`` px, inlier Gaussian (x, y);
    v: outlier box area px^2 (square box of side ``sqrt(v)``); reference_scale: px, 2D scale (paper
    definition) of the fitted data; nll_mixture / nll_gaussian: ``(17,)`` mean NLL (nats) of the
    mixture and of the single-Gaussian baseline per joint; gaussian_mu / gaussian_sigma: ``(17, 2)`` px,
    the baseline fit; iterations: ``(17,)`` EM iterations; n_samples: errors per joint; source: text.
    """

    gamma: np.ndarray
    mu: np.ndarray
    sigma: np.ndarray
    v: float = OUTLIER_VOLUME_PX2
    reference_scale: float = STANDIN_REFERENCE_SCALE_PX
    nll_mixture: np.ndarray | None = None
    nll_gaussian: np.ndarray | None = None
    gaussian_mu: np.ndarray | None = None
    gaussian_sigma: np.ndarray | None = None
    iterations: np.ndarray | None = None
    n_samples: int = 0
    source: str = ""
    meta: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        J = NUM_JOINTS
        object.__setattr__(self, "gamma", _arr(self.gamma, (J,), "gamma"))
        object.__setattr__(self, "mu", _arr(self.mu, (J, 2), "mu"))
        object.__setattr__(self, "sigma", _arr(self.sigma, (J, 2), "sigma"))
        for name, shape in (("nll_mixture", (J,)), ("nll_gaussian", (J,)), ("gaussian_mu", (J, 2)),
                            ("gaussian_sigma", (J, 2)), ("iterations", (J,))):
            val = getattr(self, name)
            if val is not None:
                object.__setattr__(self, name, _arr(val, shape, name))
        if np.any(self.gamma <= 0) or np.any(self.gamma > 1):
            raise PoseLifterError("gamma: every inlier weight must be in (0, 1]")
        if np.any(self.sigma <= 0):
            raise PoseLifterError("sigma: must be > 0 px")
        if not (self.v > 0 and self.reference_scale > 0):
            raise PoseLifterError("v and reference_scale must be > 0")

    # -- construction ---------------------------------------------------------------------------
    @classmethod
    def standin(cls) -> ErrorModel:
        """The documented stand-in: zero-mean Gaussian, 8 px per axis at scale 100 px, no outliers."""
        J = NUM_JOINTS
        return cls(gamma=np.ones(J), mu=np.zeros((J, 2)), sigma=np.full((J, 2), STANDIN_SIGMA_PX),
                   reference_scale=STANDIN_REFERENCE_SCALE_PX,
                   source="stand-in (no fitted model shipped): N(0, 8^2 px^2) per axis at 2D scale 100 px, "
                          "no outliers")

    @classmethod
    def default(cls) -> ErrorModel:
        """The shipped fit (``error_model/sh_mixture.json`` of :mod:`lifter.resources`), or :meth:`standin` if it is
        absent. A present but unreadable file is an error, not a silent fallback."""
        node = assets.asset(f"error_model/{DEFAULT_ASSET_NAME}")
        if node.is_file():
            return cls.from_json(node.read_text())
        return cls.standin()

    @classmethod
    def shipped(cls, name: str) -> ErrorModel:
        """A shipped fit by name (``"sh_mixture"``, ``"blazepose_demo"``, ...)."""
        node = assets.asset(f"error_model/{name}.json")
        if not node.is_file():
            raise PoseLifterError(f"no shipped error model {name!r} (shipped: {shipped_error_models()})")
        return cls.from_json(node.read_text())

    @classmethod
    def resolve(cls, ref: str) -> ErrorModel:
        """A shipped fit name, a JSON file path, or a training checkpoint (``.pt``) that stores the fit it trained
        with (``meta["error_model"]``, :func:`lifter.train.save_training_outputs`). A checkout's path to a shipped
        fit (``assets/error_model/NAME.json``, as the shipped networks' configs say) that is not there, as from
        another folder or an installed package, is that shipped fit."""
        if ref.endswith(".pt"):
            from .checkpoint import load_checkpoint

            stored = load_checkpoint(ref).meta.get("error_model")  # (draws nothing from the global generator)
            if not isinstance(stored, dict):
                raise PoseLifterError(f"error model {ref}: this checkpoint stores no error-model fit (a run without "
                                      "synthetic noise, or from before runs stored theirs): give the fit's JSON")
            return cls.from_dict(stored)
        path = Path(ref)
        if not path.is_file() and path.parent.parts[-2:] == ("assets", "error_model") and path.suffix == ".json" \
                and path.stem in shipped_error_models():
            warn_user(
                f"error model {ref}: no such file here; taken as the shipped fit {path.stem!r} that this path names in "
                "a checkout (a config written there; give the file itself if it was another)")
            return cls.shipped(path.stem)
        if ref.endswith(".json") or path.is_file():
            return cls.load(ref)
        return cls.shipped(ref)

    @classmethod
    def load(cls, path: str | Path) -> ErrorModel:
        try:
            text = Path(path).read_text()
        except (OSError, UnicodeDecodeError) as exc:
            raise PoseLifterError(f"error model {path}: cannot read ({exc})") from None
        return cls.from_json(text)

    def save(self, path: str | Path) -> Path:
        from .io import write_atomic  # (a security trial: it wrote through a symbolic link, and not atomically)

        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        return write_atomic(path, self.to_json())

    def baseline(self) -> ErrorModel:
        """The single-Gaussian baseline as an :class:`ErrorModel` (gamma = 1: every joint gets
        ``N(gaussian_mu, gaussian_sigma^2)``), for the Table 3 "single Gaussian" row."""
        if self.gaussian_mu is None or self.gaussian_sigma is None:
            raise PoseLifterError("this error model has no single-Gaussian baseline fit")
        return replace(self, gamma=np.ones(NUM_JOINTS), mu=self.gaussian_mu, sigma=self.gaussian_sigma,
                       source=self.source + " [single-Gaussian baseline]")

    # -- JSON ------------------------------------------------------------------------------------
    def to_dict(self) -> dict[str, Any]:
        def lst(a: np.ndarray | None) -> Any:
            return None if a is None else np.round(np.asarray(a, np.float64), 6).tolist()

        return {
            "format": FORMAT_TAG,
            "version": FORMAT_VERSION,
            "units": "image px at the reference 2D scale; v in px^2; NLL in nats per 2D error",
            "joint_names": list(JOINT_NAMES),
            "v": self.v,
            "reference_scale": self.reference_scale,
            "scale_rule": "noise *= sigma_pose / reference_scale (sigma: paper RMS radius of the clean 2D pose)",
            "level_rule": "p_out = min((1-gamma)*level, max(0.5, 1-gamma)); inlier noise = level*(mu + sigma*n); "
                          "outlier noise = U[-sqrt(v)/2, sqrt(v)/2]^2 (or 0 with outliers=False)",
            "mixture": {"gamma": lst(self.gamma), "mu": lst(self.mu), "sigma": lst(self.sigma),
                        "nll": lst(self.nll_mixture),
                        "iterations": None if self.iterations is None else [int(i) for i in self.iterations]},
            "gaussian": {"mu": lst(self.gaussian_mu), "sigma": lst(self.gaussian_sigma), "nll": lst(self.nll_gaussian)},
            "n_samples": int(self.n_samples),
            "source": self.source,
            "meta": self.meta,
        }

    def to_json(self) -> str:
        return json.dumps(self.to_dict(), indent=1)

    def sha256(self) -> str:
        """The sha256 of the parameters noise is drawn with (gamma, mu, sigma, v, the reference scale and the
        single-Gaussian baseline's mu and sigma, rounded as :meth:`to_json` writes them), not of its description,
        NLLs or meta: the same fit from a shipped name, a JSON file or a checkpoint gives the same digest
        (training checkpoints record it, ``--config`` compares)."""
        import hashlib

        d = self.to_dict()
        keep = {"v": d["v"], "reference_scale": d["reference_scale"],
                "mixture": {k: d["mixture"][k] for k in ("gamma", "mu", "sigma")},
                "gaussian": {k: (d.get("gaussian") or {}).get(k) for k in ("mu", "sigma")}}
        return hashlib.sha256(json.dumps(keep, sort_keys=True).encode()).hexdigest()

    @classmethod
    def from_json(cls, text: str) -> ErrorModel:
        try:
            d = json.loads(text)
        except json.JSONDecodeError as exc:
            raise PoseLifterError(f"error model JSON: not valid JSON ({exc})") from None
        if not isinstance(d, dict):
            raise PoseLifterError(f"error model JSON: expected an object, got {type(d).__name__}")
        return cls.from_dict(d)

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> ErrorModel:
        """The fit :meth:`to_dict` wrote."""
        if d.get("format") != FORMAT_TAG:
            raise PoseLifterError(f"error model JSON: expected format {FORMAT_TAG!r}, got {d.get('format')!r}")
        m, g = d["mixture"], d.get("gaussian", {})
        return cls(gamma=m["gamma"], mu=m["mu"], sigma=m["sigma"], v=float(d["v"]),
                   reference_scale=float(d["reference_scale"]), nll_mixture=m.get("nll"),
                   nll_gaussian=g.get("nll"), gaussian_mu=g.get("mu"), gaussian_sigma=g.get("sigma"),
                   iterations=m.get("iterations"), n_samples=int(d.get("n_samples", 0)),
                   source=d.get("source", ""), meta=d.get("meta", {}))

    # -- sampling --------------------------------------------------------------------------------
    @property
    def box_half_width(self) -> float:
        """Half the side of the outlier box, px at the reference scale (50 px for v = 100^2)."""
        return 0.5 * math.sqrt(self.v)

    def scale_factor(self, keypoints: ArrayT) -> ArrayT:
        """``s = sigma_pose / reference_scale`` ``(...)`` for clean keypoints ``(..., 17, 2)`` px (numpy or torch):
        the factor every noise component is multiplied by (module docstring, "scale rule")."""
        return pose_scale(keypoints) / self.reference_scale

    def sample(
        self,
        keypoints: ArrayLike,
        *,
        level: ArrayLike = 1.0,
        rng: np.random.Generator | int | None = None,
        outliers: bool = True,
        scale: ArrayLike | None = None,
    ) -> np.ndarray:
        """Noisy copies of clean keypoints ``(..., 17, 2)`` px, same shape, float64 (numpy front end of
        :meth:`sample_torch`, the one sampler).

        level: 0 = clean (input returned unchanged), 1 = as fitted, > 1 exaggerated (module docstring); a
            number or one level per pose ``(...)``.
        rng: a numpy Generator (or a seed); the draws are reproducible for a given generator state.
        outliers: sample the uniform component (True) or give outlier joints zero noise (authors' code).
        scale: the 2D scale ``sigma`` (px) to scale the noise with, ``(...)`` or scalar; default: that of
            ``keypoints`` (:func:`lifter.normalization.pose_scale`).
        """
        kp = as_points(keypoints, name="keypoints", dim=2, num_joints=NUM_JOINTS)
        lv = np.asarray(level, np.float64)
        if not np.all(np.isfinite(lv)) or np.any(lv < 0):
            raise PoseLifterError(f"level: must be finite numbers >= 0, got {level}")
        if not np.any(lv):
            return kp.copy()
        if not isinstance(rng, np.random.Generator):
            rng = np.random.default_rng(rng)
        gen = torch.Generator().manual_seed(int(rng.integers(0, 2**62)))
        lead = kp.shape[:-2]
        sc = None if scale is None else torch.from_numpy(np.broadcast_to(np.asarray(scale, np.float64), lead).copy())
        levels = torch.from_numpy(np.broadcast_to(lv, lead).copy())
        out = self.sample_torch(torch.from_numpy(np.array(kp)), level=levels, generator=gen, outliers=outliers,
                                scale=sc)
        return out.numpy()

    def sample_torch(self, keypoints: torch.Tensor, *, level: float | torch.Tensor = 1.0,
                     generator: torch.Generator | None = None, outliers: bool = True,
                     scale: torch.Tensor | None = None) -> torch.Tensor:
        """The sampler: noisy copies of clean keypoints ``(..., 17, 2)`` px (any float dtype, any device).

        Per joint independently, an outlier with probability ``min((1 - gamma) * level, max(0.5, 1 - gamma))``
        gets ``s * U[-50, 50]^2`` px (or nothing with ``outliers=False``); an inlier gets
        ``s * level * (mu + sigma * n)``; ``s = sigma_pose / reference_scale``. ``level`` is a number or a tensor
        ``(...)`` (one level per pose); draws come from ``generator``.
        """
        kp = keypoints
        dt, dev = kp.dtype, kp.device
        lv = torch.as_tensor(level, dtype=dt, device=dev)
        lv = lv.expand(kp.shape[:-2])[..., None]  # (..., 1): one level per pose
        mu = torch.as_tensor(np.array(self.mu), dtype=dt, device=dev)
        sg = torch.as_tensor(np.array(self.sigma), dtype=dt, device=dev)
        p_out = outlier_probability(self.gamma, lv)  # (..., 17)
        s = self.scale_factor(kp) if scale is None else scale.to(dt) / self.reference_scale  # (...)
        n = torch.randn(kp.shape, generator=generator, dtype=dt, device=dev)
        is_out = torch.rand(kp.shape[:-1], generator=generator, dtype=dt, device=dev) < p_out
        u = (torch.rand(kp.shape, generator=generator, dtype=dt, device=dev) - 0.5) * (2 * self.box_half_width)
        noise = lv[..., None] * (mu + sg * n)
        noise = torch.where(is_out[..., None], u if outliers else torch.zeros_like(u), noise)
        return kp + s[..., None, None] * noise


def normalized_errors(detections: np.ndarray, ground_truth: np.ndarray, *,
                      reference_scale: float | None = None) -> tuple[np.ndarray, np.ndarray, float]:
    """Errors ``(N, 17, 2)`` px rescaled to the reference scale, the per-sample GT scale ``(N,)`` px and the
    reference scale (median GT scale unless given): ``e = (det - gt) * reference_scale / sigma_gt``."""
    det = as_points(detections, name="detections", dim=2)
    gt = as_points(ground_truth, name="ground_truth", dim=2)
    scale = pose_scale(gt)
    ref = float(np.median(scale)) if reference_scale is None else float(reference_scale)
    return (det - gt) * (ref / scale)[:, None, None], scale, ref


def em_not_converged(model: ErrorModel) -> list[str]:
    """The joints whose EM stopped at ``max_iter`` before its log-likelihood settled (``meta["em"]["converged"]``
    of :func:`fit_error_model`; a fit that does not say: none)."""
    flags = (model.meta.get("em") or {}).get("converged")
    if not isinstance(flags, list) or len(flags) != NUM_JOINTS:
        return []
    return [JOINT_NAMES[j] for j, ok in enumerate(flags) if not ok]


def fit_error_model(detections: np.ndarray, ground_truth: np.ndarray, *, source: str = "",
                    tol: float = 1e-7, max_iter: int = 1000, progress: bool = True,
                    meta: dict[str, Any] | None = None) -> ErrorModel:
    """Fit the mixture and the single-Gaussian baseline per joint to detections vs ground truth, both
    ``(N, 17, 2)`` px in the H36M joint order, with the scale rule of the module docstring."""
    e, _, ref = normalized_errors(detections, ground_truth)
    J = NUM_JOINTS
    gamma, iters = np.zeros(J), np.zeros(J, int)
    mu, sigma, gmu, gsig = (np.zeros((J, 2)) for _ in range(4))
    nll_m, nll_g = np.zeros(J), np.zeros(J)
    converged = [False] * J
    for j in tqdm(range(J), desc="EM per joint", unit="joint", disable=None if progress else True):
        gmu[j], gsig[j], nll_g[j] = fit_gaussian(e[:, j])
        f = fit_mixture(e[:, j], tol=tol, max_iter=max_iter)
        gamma[j], mu[j], sigma[j], nll_m[j], iters[j] = f.gamma, f.mu, f.sigma, f.nll, f.iterations
        converged[j] = f.converged
    m = dict(meta or {})
    # (whether each joint's EM met tol before max_iter: a researcher trial's --max-iter 2 fit said "iters 2" for
    # every joint and nothing more; em_not_converged names them)
    m.update({"em": {"init": "single-Gaussian ML fit, gamma = 0.9", "tol_nats_per_sample": tol, "max_iter": max_iter,
                     "converged": converged}})
    return ErrorModel(gamma=gamma, mu=mu, sigma=sigma, v=OUTLIER_VOLUME_PX2, reference_scale=ref,
                      nll_mixture=nll_m, nll_gaussian=nll_g, gaussian_mu=gmu, gaussian_sigma=gsig,
                      iterations=iters, n_samples=int(e.shape[0]), source=source, meta=m)
