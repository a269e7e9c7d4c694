"""The PoseLifter network and its configuration.

:class:`ModelConfig` names everything that fixes a trained network's shape and conventions: the input
space and features of :mod:`lifter.codec`, the depth parametrization, the conditioning, and the MLP's size.

Architecture (spec §5): ``Linear(F -> W)`` stem (no activation), ``num_blocks`` pre-activation residual
blocks ``x + Linear(ReLU(Dropout(BN(Linear(ReLU(Dropout(BN(x))))))))``, and a ``Linear(W -> 49)`` head.
The network maps the codec's features ``(B, F)`` to its *standardized* outputs ``(B, 49)``; the codec
turns those into millimetres (:meth:`lifter.codec.PoseCodec.destandardize`) and back into a pose and a
root (:meth:`lifter.codec.PoseCodec.decode`).
"""

from __future__ import annotations

import math
import weakref
from dataclasses import asdict, dataclass, fields
from typing import Any, Final, Literal, get_args

import numpy as np
import torch
from torch import nn
from torch.nn import functional as F

from ._checks import PoseLifterError
from .normalization import NORM_MODES, SCALE_DEFINITIONS, NormMode, ScaleDefinition, feature_mirror, num_features
from .skeleton import NUM_JOINTS, mirror

InputSpace = Literal["pixel", "camera"]
DepthTarget = Literal["canonical", "absolute", "size"]
Conditioning = Literal["none", "source"]
Symmetry = Literal["none", "mirror"]
View = Literal["camera", "look_at"]
NUM_OUTPUTS: Final[int] = 3 * (NUM_JOINTS - 1) + 1
MAX_WIDTH: Final[int] = 8192
MAX_BLOCKS: Final[int] = 16
"""Bounds on :class:`ModelConfig` sizes, checked before anything is allocated (a checkpoint's config is
untrusted input)."""


@dataclass(frozen=True)
class ModelConfig:
    """The network's shape and input/output conventions. Validated on construction.

    input_space: ``"camera"``: the codec maps the 2D through the intrinsics to the reference camera
        (focal F0 = 1000 px, principal point 0) before the normalization layer, so resolution and focal
        length are exact symmetries. ``"pixel"``: the paper's layer on image pixels minus the principal point.
    depth_target: what the network predicts for the root depth, in the input space's camera:
        ``"canonical"`` ``Z * F0 / alpha_in`` mm (PoseLifter; in the reference camera alpha_in = F0, so it is Z);
        ``"absolute"`` Z mm (pixel space only: the paper's "w/o canonical depth");
        ``"size"`` ``Z * sigma_in / alpha_in`` mm, the person's 2D scale in mm (weak perspective), from which
        ``Z = size * alpha_in / sigma_in``.
    conditioning: ``"source"`` appends one input feature, 1 for exact 2D (``source="clean"``) and 0 for
        detector output (``"detected"``).
    mode, scale_definition: the normalization layer's features and 2D scale (:mod:`lifter.normalization`).
    symmetry: ``"mirror"``: the network is mirror-equivariant by construction (:class:`MirrorCoupledLinear`):
        two weight-shared streams read the features and the features of the mirror image, are coupled in
        every hidden layer, and the head averages the two streams' outputs with the mirror mapped back. One
        pass then gives what flip-test averaging gives with two, and ``width`` is the width of each stream.
        ``"none"``: the paper's MLP.
    view: ``"camera"``: the network reads the 2D and predicts the pose in the (reference) camera's frame.
        ``"look_at"`` (``input_space="camera"`` only): the codec first turns the reference camera about its centre
        to look at the 2D root (:meth:`lifter.codec.PoseCodec.look_at`), an exact change of view, so the network
        reads the pose as if it stood at the image centre, predicts the relative pose in that camera's frame and
        the root's depth along its axis, and the codec turns them back. Where the person stands in the image then
        reaches the network only as the small in-plane turn that looking at an off-centre root gives the turned
        camera (so a camera pan or tilt changes the input only by such a turn). Pinhole (undistorted) 2D.
    """

    width: int = 1024
    num_blocks: int = 2
    dropout: float = 0.25
    mode: NormMode = "both"
    scale_definition: ScaleDefinition = "paper"
    input_space: InputSpace = "camera"
    depth_target: DepthTarget = "canonical"
    conditioning: Conditioning = "source"
    symmetry: Symmetry = "none"
    view: View = "camera"

    def __post_init__(self) -> None:
        for name, lo, hi in (("width", 1, MAX_WIDTH), ("num_blocks", 1, MAX_BLOCKS)):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, int) or not lo <= v <= hi:
                raise PoseLifterError(f"model config: {name} must be an integer in [{lo}, {hi}], got {v!r}")
        d = self.dropout
        if isinstance(d, bool) or not isinstance(d, (int, float)) or not 0.0 <= d < 1.0:
            raise PoseLifterError(f"model config: dropout must be a number in [0, 1), got {d!r}")
        for name, allowed in (("mode", NORM_MODES), ("scale_definition", SCALE_DEFINITIONS),
                              ("input_space", get_args(InputSpace)), ("depth_target", get_args(DepthTarget)),
                              ("conditioning", get_args(Conditioning)), ("symmetry", get_args(Symmetry)),
                              ("view", get_args(View))):
            if getattr(self, name) not in allowed:
                raise PoseLifterError(f"model config: {name} is {getattr(self, name)!r}; expected one of "
                                      f"{list(allowed)}")
        if self.input_space == "camera" and self.depth_target == "absolute":
            raise PoseLifterError("model config: in the reference camera the canonical depth is the absolute depth; "
                                  "use depth_target='canonical' (or 'size') with input_space='camera'")
        if self.view == "look_at" and self.input_space != "camera":
            raise PoseLifterError("model config: view='look_at' needs the viewing rays: use input_space='camera'")
        if self.depth_target == "size" and self.mode not in ("scale", "both"):
            raise PoseLifterError("model config: depth_target='size' needs the scale feature (mode 'scale' or 'both')")

    @property
    def num_features(self) -> int:
        """Input features: the normalization layer's, plus one for the source flag."""
        return num_features(self.mode) + (1 if self.conditioning == "source" else 0)

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> ModelConfig:
        """Build from a dict, refusing unknown keys (all checks run before any network is built)."""
        if not isinstance(d, dict):
            raise PoseLifterError(f"model config must be a dict, got {type(d).__name__}")
        unknown = set(d) - {f.name for f in fields(cls)}
        if unknown:
            raise PoseLifterError(f"model config: unknown keys {sorted(unknown)}")
        return cls(**d)


class MirrorCoupledLinear(nn.Module):
    """The hidden layer of a mirror-equivariant network (``symmetry="mirror"``).

    Input ``(2B, W)``: the rows of stream 0 (the features) then those of stream 1 (the mirrored features).
    With ``s = h0 + h1`` and ``d = h0 - h1``, the output is ``y0 = U s + V d + b`` and ``y1 = U s - V d + b``:
    swapping the streams swaps the outputs, so the layer commutes with the mirror for any ``U`` and ``V``
    (``W x W`` each). It is ``[[U + V, U - V], [U - V, U + V]]`` on the stacked streams, computed as two
    ``W x W`` products instead of one ``2W x 2W``: half the weights and multiply-adds of a width-2W layer.
    Initialized so that the weights ``U + V`` and ``U - V`` have the variance of PyTorch's default
    ``nn.Linear(2W, W)`` weights; the bias is drawn from the same ``U(-0.5 / sqrt(W), 0.5 / sqrt(W))`` as ``U``
    and ``V`` (half the variance of that layer's bias).
    """

    def __init__(self, width: int) -> None:
        super().__init__()
        self.weight_sum = nn.Parameter(torch.empty(width, width))
        self.weight_diff = nn.Parameter(torch.empty(width, width))
        self.bias = nn.Parameter(torch.empty(width))
        bound = 0.5 / math.sqrt(width)  # U + V then has the variance of a U(-1/sqrt(2W), 1/sqrt(2W)) weight
        for t in (self.weight_sum, self.weight_diff):
            nn.init.uniform_(t, -bound, bound)
        nn.init.uniform_(self.bias, -bound, bound)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return couple_streams(x, lambda s: F.linear(s, self.weight_sum, self.bias),
                              lambda d: F.linear(d, self.weight_diff))


def couple_streams(x: torch.Tensor, on_sum: Any, on_diff: Any) -> torch.Tensor:
    """The coupling of :class:`MirrorCoupledLinear` with the two products given as callables: rows ``[h0; h1]``
    -> ``[on_sum(h0 + h1) + on_diff(h0 - h1); on_sum(h0 + h1) - on_diff(h0 - h1)]``."""
    if x.shape[0] % 2:
        raise ValueError(f"MirrorCoupledLinear: expected the two streams stacked, got {x.shape[0]} rows")
    h0, h1 = x.chunk(2)
    us, vd = on_sum(h0 + h1), on_diff(h0 - h1)
    return torch.cat([us + vd, us - vd])


class QuantizedCoupledLinear(nn.Module):
    """A :class:`MirrorCoupledLinear` whose two products use int8 weights (PyTorch dynamic quantization), for
    :meth:`lifter.Lifter.quantized`."""

    def __init__(self, layer: MirrorCoupledLinear) -> None:
        super().__init__()
        w = layer.weight_sum.shape[0]
        # (float32 whatever torch's default dtype: quantize_dynamic keeps a float64 layer's inputs float64)
        on_sum, on_diff = nn.Linear(w, w, dtype=torch.float32), nn.Linear(w, w, bias=False, dtype=torch.float32)
        with torch.no_grad():
            on_sum.weight.copy_(layer.weight_sum)
            on_sum.bias.copy_(layer.bias)
            on_diff.weight.copy_(layer.weight_diff)
        pair = nn.ModuleDict({"sum": on_sum, "diff": on_diff})
        self.pair = torch.ao.quantization.quantize_dynamic(pair, {nn.Linear}, dtype=torch.qint8)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return couple_streams(x, self.pair["sum"], self.pair["diff"])


class ResidualBlock(nn.Module):
    def __init__(self, width: int, dropout: float, *, coupled: bool = False) -> None:
        super().__init__()

        def linear() -> nn.Module:
            return MirrorCoupledLinear(width) if coupled else nn.Linear(width, width)

        self.body = nn.Sequential(
            nn.BatchNorm1d(width),
            nn.Dropout(dropout),
            nn.ReLU(inplace=True),
            linear(),
            nn.BatchNorm1d(width),
            nn.Dropout(dropout),
            nn.ReLU(inplace=True),
            linear(),
        )

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return x + self.body(x)


def output_mirror(target_mean: Any = None, target_std: Any = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The mirror image in the network's standardized output space: a network output ``z`` ``(..., 49)`` of a
    mirrored input, mapped back, is ``z[..., perm] * scale + offset``. Raw outputs (``mean + std * z``, mm) are
    mirrored as :meth:`lifter.codec.PoseCodec.mirror_output` does (the pose by :func:`lifter.skeleton.mirror`,
    the depth kept). Returns ``perm`` int64 and ``scale``, ``offset`` float32, all ``(49,)``; an involution."""
    mean = np.zeros(NUM_OUTPUTS) if target_mean is None else np.asarray(target_mean, np.float64)
    std = np.ones(NUM_OUTPUTS) if target_std is None else np.asarray(target_std, np.float64)
    probe = np.zeros((NUM_JOINTS, 3))
    probe[1:] = np.arange(1, NUM_OUTPUTS, dtype=np.float64).reshape(NUM_JOINTS - 1, 3)
    flat = mirror(probe)[1:].reshape(-1)
    perm = np.append(np.abs(flat).astype(np.int64) - 1, NUM_OUTPUTS - 1)
    sign = np.append(np.sign(flat), 1.0)
    scale = sign * std[perm] / std
    offset = (sign * mean[perm] - mean) / std
    return perm, scale.astype(np.float32), offset.astype(np.float32)


class PoseLifterNet(nn.Module):
    """Features ``(B, F)`` (:meth:`lifter.codec.PoseCodec.encode`) -> standardized outputs ``(B, 49)``.

    Hidden linear layers use PyTorch's default (Kaiming-uniform) initialization; the head is
    initialized N(0, 1e-3) with zero bias, so that at step 0 the de-standardized output is the
    training-target mean. Under ``torch.autocast`` only the residual blocks run in reduced precision:
    the stem (which reads pixel-precise features) and the head (millimetre outputs) stay float32.

    ``symmetry="mirror"``: the stem and head are shared by two streams, the features and the mirrored
    features (buffers ``in_perm``, ``in_sign``: :func:`lifter.normalization.feature_mirror`), the hidden layers
    are :class:`MirrorCoupledLinear`, BatchNorm's statistics are shared by the streams, and the output is the
    mean of stream 0's and stream 1's mirrored back (buffers ``out_perm``, ``out_scale``, ``out_offset``:
    :func:`output_mirror` of the codec's target statistics, set by :meth:`set_target_statistics`). In eval
    mode ``net(mirrored features)`` is then exactly the mirror of ``net(features)``.
    """

    in_perm: torch.Tensor
    in_sign: torch.Tensor
    out_perm: torch.Tensor
    out_scale: torch.Tensor
    out_offset: torch.Tensor

    def __init__(self, config: ModelConfig | None = None) -> None:
        super().__init__()
        config = config or ModelConfig()
        self.config = config
        mirrored = config.symmetry == "mirror"
        self.stem = nn.Linear(config.num_features, config.width)
        self.blocks = nn.Sequential(*[ResidualBlock(config.width, config.dropout, coupled=mirrored)
                                      for _ in range(config.num_blocks)])
        self.head = nn.Linear(config.width, NUM_OUTPUTS)
        if not self.head.weight.is_meta:  # (a meta net, for shapes only, has no values: its first normal_ costs ~1.5 s)
            nn.init.normal_(self.head.weight, std=1e-3)
        nn.init.zeros_(self.head.bias)
        if mirrored:
            perm, sign = feature_mirror(config.mode, num_extra=config.num_features - num_features(config.mode))
            self.register_buffer("in_perm", torch.from_numpy(perm))
            self.register_buffer("in_sign", torch.from_numpy(sign))
            self.register_buffer("out_perm", torch.zeros(NUM_OUTPUTS, dtype=torch.int64))
            self.register_buffer("out_scale", torch.zeros(NUM_OUTPUTS))
            self.register_buffer("out_offset", torch.zeros(NUM_OUTPUTS))
            self.set_target_statistics(None, None)

    def set_target_statistics(self, target_mean: Any, target_std: Any) -> None:
        """Set the output mirror of a ``symmetry="mirror"`` network from the codec's target statistics
        ``(49,)`` mm (None: 0 and 1). No-op for other networks, whose outputs do not depend on them, and when the
        buffers hold these values already. Changed buffers are replaced, not written in place (so a network
        made under ``torch.inference_mode()`` can be given new statistics outside it)."""
        if self.config.symmetry != "mirror":
            return
        for name, value in zip(("out_perm", "out_scale", "out_offset"), output_mirror(target_mean, target_std)):
            old = getattr(self, name)
            if old.is_meta:
                continue  # a network being built for a checkpoint: loading it gives the values
            new = torch.from_numpy(value).to(device=old.device, dtype=old.dtype)
            if not torch.equal(old, new):
                setattr(self, name, new)

    def forward(self, features: torch.Tensor) -> torch.Tensor:
        dev = features.device.type
        mirrored = self.config.symmetry == "mirror"
        with torch.autocast(dev, enabled=False):
            x = features.float()
            if mirrored:
                x = torch.cat([x, x[:, self.in_perm] * self.in_sign])
            h = self.stem(x)
        h = self.blocks(h)
        with torch.autocast(dev, enabled=False):
            out = self.head(h.float())
            if mirrored:
                g0, g1 = out.chunk(2)
                out = 0.5 * (g0 + g1[:, self.out_perm] * self.out_scale + self.out_offset)
            return out


# ------------------------------------------------------------------------------------------------
# One pose through numpy's BLAS
# ------------------------------------------------------------------------------------------------


def _numpy_tensors(net: PoseLifterNet) -> tuple[list[torch.Tensor], list[float]] | None:
    """The tensors :func:`forward_numpy` reads, in a fixed order: stem weight and bias; per block the first
    BatchNorm's weight, bias, running mean and variance, the first hidden layer's weight and bias (weight_sum,
    weight_diff and bias for a :class:`MirrorCoupledLinear`), the same for the second pair; head weight and
    bias; for ``symmetry="mirror"`` then ``in_perm``, ``in_sign``, ``out_perm``, ``out_scale``, ``out_offset``.
    Looked up through the modules' own dictionaries on every call (so replaced layers or tensors are always the
    current ones); and the BatchNorm epsilons, in the same order. None if a layer is not the plain float layer
    its config builds (``nn.Linear`` / :class:`MirrorCoupledLinear` / ``nn.BatchNorm1d`` / ``nn.ReLU``, or a
    block not a plain :class:`ResidualBlock`) or a BatchNorm or Dropout is in training mode."""
    mods = net._modules
    stem, blocks, head = mods.get("stem"), mods.get("blocks"), mods.get("head")
    if (type(stem) is not nn.Linear or type(head) is not nn.Linear or type(blocks) is not nn.Sequential
            or type(net).forward is not PoseLifterNet.forward):
        return None  # (a subclass that changes the forward pass runs as the module it is)
    mirrored = net.config.symmetry == "mirror"
    hidden, names = (MirrorCoupledLinear, ("weight_sum", "weight_diff", "bias")) if mirrored else \
        (nn.Linear, ("weight", "bias"))
    out = [stem._parameters["weight"], stem._parameters["bias"]]
    eps = []
    for block in blocks._modules.values():
        body = block._modules.get("body") if block is not None else None
        layers: list[Any] = list(body._modules.values()) if body is not None else []
        if len(layers) != 8:
            return None
        bn1, drop1, act1, lin1, bn2, drop2, act2, lin2 = layers
        if (type(block) is not ResidualBlock or type(bn1) is not nn.BatchNorm1d or type(bn2) is not nn.BatchNorm1d
                or type(lin1) is not hidden or type(lin2) is not hidden or type(act1) is not nn.ReLU
                or type(act2) is not nn.ReLU or bn1.training or bn2.training or drop1.training or drop2.training):
            return None
        for bn, lin in ((bn1, lin1), (bn2, lin2)):
            p, b = bn._parameters, bn._buffers
            out += [p["weight"], p["bias"], b["running_mean"], b["running_var"]]
            out += [lin._parameters[n] for n in names]
            eps.append(float(bn.eps))
    out += [head._parameters["weight"], head._parameters["bias"]]
    if mirrored:
        out += [net._buffers[n] for n in ("in_sign", "out_scale", "out_offset")]
    if any(t is None or t.dtype != torch.float32 for t in out):
        return None
    if mirrored:
        perms = [net._buffers[n] for n in ("in_perm", "out_perm")]
        if any(t is None or t.dtype != torch.int64 for t in perms):
            return None
        out = out[:-3] + [perms[0], out[-3], perms[1], out[-2], out[-1]]
    return out, eps  # type: ignore[return-value]


_NUMPY_VIEWS: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()
"""net -> (key, numpy views of :func:`_numpy_tensors`); the views share memory with the tensors, so
in-place changes are seen without a rebuild, and the key (tensor identities and storage addresses)
catches replaced tensors or storage."""


def _layout(t: list[Any], eps: list[float], mirrored: bool) -> tuple[tuple, list[tuple], tuple, tuple]:
    """The flat list of :func:`_numpy_tensors` (torch tensors or their numpy views) in its structure:
    ``(stem (W, b), blocks, head (W, b), mirror maps)``; each block ``(bn1, first layer, bn2, second layer)``
    with a BatchNorm as ``(gamma, beta, running mean, running var, eps)`` and a layer as ``(W, b)`` or, for a
    mirror network, ``(U, V, b)``; the maps ``(in_perm, in_sign, out_perm, out_scale, out_offset)`` or ``()``.
    The one reader of that order."""
    k = 3 if mirrored else 2
    blocks = []
    i = 2
    for e in range(0, len(eps), 2):
        blocks.append(((*t[i:i + 4], eps[e]), tuple(t[i + 4:i + 4 + k]), (*t[i + 4 + k:i + 8 + k], eps[e + 1]),
                       tuple(t[i + 8 + k:i + 8 + 2 * k])))
        i += 8 + 2 * k
    return tuple(t[:2]), blocks, tuple(t[i:i + 2]), tuple(t[i + 2:])


def forward_numpy(net: PoseLifterNet, features: np.ndarray) -> np.ndarray | None:
    """:meth:`PoseLifterNet.forward` in eval mode, in numpy: features ``(B, F)`` float32 -> standardized
    outputs ``(B, 49)``.

    For one pose the network is a chain of matrix-vector products, which numpy's BLAS runs with less
    overhead than torch's CPU kernels (``benchmarks/bench_lift.py`` times both). It reads the live
    weights through numpy views that share memory with the parameters (no copies), so any change to
    the net, in place or by replacing tensors or layers, is seen on the next call; BatchNorm is applied
    as the per-channel affine map of its running statistics. Returns None when a layer is not a plain
    float32 layer of its config (e.g. quantized) or a BatchNorm or Dropout is in training mode: use the
    module then.
    """
    found = _numpy_tensors(net)
    if found is None:
        return None
    tensors, eps = found
    return _forward_chain(net, _numpy_views(net, tensors), eps, features)


def _numpy_views(net: PoseLifterNet, tensors: list[torch.Tensor]) -> list[np.ndarray]:
    """Numpy views of :func:`_numpy_tensors`'s tensors (shared memory), cached per network and rebuilt when a tensor
    or its storage is replaced."""
    key = tuple((id(t), t.data_ptr()) for t in tensors)
    cached = _NUMPY_VIEWS.get(net)
    if cached is None or cached[0] != key:
        cached = (key, [t.detach().numpy() for t in tensors])
        _NUMPY_VIEWS[net] = cached  # one assignment: concurrent readers see the old or the new pair
    return cached[1]


def _forward_chain(net: PoseLifterNet, v: list[Any], eps: list[float], features: np.ndarray) -> np.ndarray:
    """The numpy chain of :func:`forward_numpy` (or, with packed matrices in ``v``, :func:`forward_packed`)."""
    if net.config.symmetry == "mirror":
        if len(features) == 0:
            return np.zeros((0, NUM_OUTPUTS), np.float32)
        return _forward_numpy_mirror(v, eps, features)
    return _forward_numpy_rows(v, eps, features)


# ------------------------------------------------------------------------------------------------
# A few rows through float16-packed weight matrices (fbgemm)
# ------------------------------------------------------------------------------------------------

PACKED_MAX_ROWS: Final[int] = 192
"""Batches up to this many network rows run through float16-packed copies of the weight matrices
(:func:`forward_packed`), where the network's matrices are exactly float16 numbers (every shipped network: their
files store float16). ``python benchmarks/bench_packed_rows.py`` times the default both ways, alternately
(``docs/results/bench_packed_rows.txt``, a 2-core AVX2 VM, one thread): the float32 paths took 1.64x the packed time
for one pose, 1.36x for 16 poses, 1.10-1.17x for 64-65 (the app's drag: a pose and its 64 noisy draws, 130 rows),
1.07x for 96 poses (192 rows) and 1.02-1.04x beyond, where the gain ends (the batched benchmark's 256 poses, 512 and
256 rows, stay on the float32 path it has always measured)."""

_PACKED: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()
"""net -> (key, {index in :func:`_numpy_tensors`: packed matrix} or None: not float16-exact, probe rows); the key
holds every weight matrix's identity, storage address and version counter, the probe rows each matrix's first and
last row as packed."""

_PACKING: dict[str, bool] = {}
"""Whether this torch build packs float16 matrices (fbgemm) under each quantized engine, probed once per engine."""


def fp16_packing_available() -> bool:
    """Whether this torch build, under its current quantized engine (``torch.backends.quantized.engine``), has
    fbgemm's float16-packed matrix products (``quantized::linear_prepack_fp16``: x86 CPU builds do under the default
    engine; "qnnpack" and "onednn" do not): probed once per engine; without them :func:`forward_packed` steps aside."""
    engine = str(torch.backends.quantized.engine)
    ok = _PACKING.get(engine)
    if ok is None:
        try:
            packed = torch.ops.quantized.linear_prepack_fp16(torch.ones(2, 2), None)
            ok = bool(torch.equal(torch.ops.quantized.linear_dynamic_fp16(torch.ones(1, 2), packed),
                                  torch.full((1, 2), 2.0)))
        except (RuntimeError, AttributeError, NotImplementedError):
            ok = False
        _PACKING[engine] = ok
    return ok


class _PackedMatrix:
    """A weight matrix ``(out, in)`` as fbgemm's float16-packed copy: ``x (R, in) float32 -> x @ W.T (R, out)``
    float32, the products summed in float32 (only the stored weights are float16: exact for float16 weights)."""

    __slots__ = ("_packed",)

    def __init__(self, w: torch.Tensor) -> None:
        self._packed = torch.ops.quantized.linear_prepack_fp16(w.detach().contiguous(), None)

    def __call__(self, x: np.ndarray) -> np.ndarray:
        t = torch.from_numpy(np.ascontiguousarray(x, dtype=np.float32))
        return torch.ops.quantized.linear_dynamic_fp16(t, self._packed).numpy()


def forward_packed(net: PoseLifterNet, features: np.ndarray) -> np.ndarray | None:
    """:func:`forward_numpy` with each weight matrix a float16-packed copy (fbgemm's matrix products read half the
    bytes of float32, and one pose is bound by reading the weights): the same outputs up to float32 rounding, where
    every matrix of the network is exactly float16 numbers. Features ``(R, F)`` float32, at most
    :data:`PACKED_MAX_ROWS` rows, where torch runs on one thread (``torch.set_num_threads(1)``, as on a shared machine
    anyway): fbgemm splits these small products over torch's threads, and on a busy 2-core machine one pose then took
    4-128 ms instead of 2 (a review; setting one thread around the products is no cure: ``torch.set_num_threads``
    also sets the count every thread that starts meanwhile takes). With more threads the float32 paths run.

    The biases, BatchNorm statistics and epsilons are read live on every call, as :func:`forward_numpy` does. The
    packed matrices are rebuilt when a matrix is replaced or gets new storage, when its version counter moves (a torch
    operation on it: in place under ``torch.no_grad()``, ``load_state_dict``, a plain optimizer step), and when its
    first or last row no longer holds what was packed (checked on every call, a few microseconds: this catches the
    writes that bypass the version counter and touch every row, such as a fused optimizer step, ``.data.mul_``, a
    numpy view or storage write of the whole matrix). A sparse change elsewhere written through ``.data``, a numpy
    view or the storage is not seen: :func:`drop_packed` (or :meth:`lifter.Lifter.refresh`) then. Returns None (use
    :func:`forward_numpy` or the module) when the rows are too many, torch runs on more than one thread, the packing
    is not available, a layer is not a
    plain float32 layer of its config or in training mode, a matrix is not finite float16 numbers (a network trained
    and saved with ``--fp32-weights``) or is an inference tensor (made under ``torch.inference_mode()``, which keeps
    no version counter)."""
    if len(features) > PACKED_MAX_ROWS or torch.get_num_threads() != 1 or not fp16_packing_available():
        return None
    found = _numpy_tensors(net)
    if found is None:
        return None
    tensors, eps = found
    index = [i for i, t in enumerate(tensors) if t.ndim == 2]
    if any(tensors[i].is_inference() for i in index):
        return None  # (made under torch.inference_mode(): no version counter to see changes by)
    views = _numpy_views(net, tensors)
    key = tuple((id(tensors[i]), tensors[i].data_ptr(), tensors[i]._version) for i in index)
    cached = _PACKED.get(net)
    if cached is None or cached[0] != key or not all(  # (bytes: 0.2 us a row, np.array_equal 2.5)
            views[i][0].tobytes() == first and views[i][-1].tobytes() == last
            for i, (first, last) in zip(index, cached[2])):
        packs = None
        with torch.no_grad():
            if all(bool(torch.isfinite(tensors[i]).all()) and torch.equal(
                    tensors[i], tensors[i].to(torch.float16).to(torch.float32)) for i in index):
                try:
                    packs = {i: _PackedMatrix(tensors[i]) for i in index}
                except RuntimeError:  # (a quantized engine that cannot pack: the float32 paths)
                    return None
        cached = (key, packs, [(views[i][0].tobytes(), views[i][-1].tobytes()) for i in index])
        _PACKED[net] = cached  # one assignment: concurrent readers see the old or the new triple
    packs = cached[1]
    if packs is None:
        return None
    return _forward_chain(net, [packs.get(i, a) for i, a in enumerate(views)], eps, features)


def drop_packed(net: PoseLifterNet) -> None:
    """Forget ``net``'s float16-packed matrices (:func:`forward_packed` packs them again from the live weights on its
    next call): after a sparse change to a matrix through ``.data``, a numpy view or its storage, which neither the
    version counters nor the first-and-last-row check see."""
    _PACKED.pop(net, None)


def _bn_affine_np(bn: tuple) -> tuple[np.ndarray, np.ndarray]:
    """A BatchNorm ``(gamma, beta, mean, var, eps)`` of :func:`_layout` as ``h * s + c`` (numpy)."""
    g, beta, mean, var, eps = bn
    s = g / np.sqrt(var + eps)
    return s, beta - mean * s


_BLOCK_BYTES: Final[int] = 1 << 20
"""Row blocks of a hidden weight matrix in :func:`_matvec_rows`: small enough to stay in a core's L2 cache
while every input row is multiplied with them."""


def _matvec_rows(w: np.ndarray, x: np.ndarray) -> np.ndarray:
    """``x @ w.T`` for a few rows ``x`` ``(R, in)`` and a weight ``w`` ``(out, in)``, as matrix-vector
    products. OpenBLAS runs a ``(1, W) @ (W, W)`` product as a matrix-vector product, but a ``(2, W)`` one as
    a general product that first packs the whole weight matrix (slower than two rows on their own). Two rows
    one after the other read the weights twice from memory; here each block of ``w``'s rows is read once and
    multiplied with every row of ``x`` while it is in cache (flip-test averaging sends two rows for one pose;
    ``benchmarks/bench_lift.py`` times it). A packed matrix (:func:`forward_packed`) multiplies all rows itself."""
    if isinstance(w, _PackedMatrix):
        return w(x)
    if len(x) == 1:
        return x @ w.T
    out = np.empty((len(x), w.shape[0]), np.result_type(x, w))
    step = max(1, _BLOCK_BYTES // max(1, w.shape[1] * w.itemsize))
    for s in range(0, w.shape[0], step):
        block = w[s:s + step]
        for r in range(len(x)):
            np.matmul(block, x[r], out=out[r, s:s + step])
    return out


def _forward_numpy_rows(v: list[np.ndarray], eps: list[float], features: np.ndarray) -> np.ndarray:
    """The chain of :func:`forward_numpy` on ``features`` ``(B, F)`` (a few rows) with the weight views ``v``."""
    (w0, b0), blocks, (wh, bh), _ = _layout(v, eps, False)
    h = _product(w0, features) + b0
    for bn1, (w1, b1), bn2, (w2, b2) in blocks:
        s1, c1 = _bn_affine_np(bn1)
        s2, c2 = _bn_affine_np(bn2)
        y = np.maximum(h * s1 + c1, 0.0)
        y = np.maximum((_matvec_rows(w1, y) + b1) * s2 + c2, 0.0)
        h = h + (_matvec_rows(w2, y) + b2)
    return _product(wh, h) + bh


def _product(w: Any, x: np.ndarray) -> np.ndarray:
    """``x @ w.T`` for the stem and head: numpy's product, or a packed matrix's (:func:`forward_packed`)."""
    return w(x) if isinstance(w, _PackedMatrix) else x @ w.T


# ------------------------------------------------------------------------------------------------
# Batches through torch, in cache-sized slices
# ------------------------------------------------------------------------------------------------

FOLDED_ROWS: Final[int] = 512
""":func:`forward_folded` runs a batch in slices of this many activation rows (a mirror network's two
streams count as two: 256 poses): the activations of a slice stay in cache between the layers, and the
hidden activations take the same memory for any batch (the features and outputs still grow with it;
:meth:`lifter.Lifter.lift` bounds those by its chunks; ``benchmarks/bench_lift.py``, ``benchmarks/bench_memory.py``)."""

def _fold(net: PoseLifterNet) -> list[Any] | None:
    """The tensors :func:`forward_folded` uses: ``[stem (W, b), blocks, head (W, b), mirror maps]``, each
    block ``(s1, c1, first layer, s2, c2, second layer)`` with each BatchNorm as the per-channel affine map
    ``h * s + c`` of its running statistics, and the first hidden layer's bias moved into ``c2``. Only these
    vectors are computed (on every call, so nothing can go stale); the weights are the live parameters. None
    when :func:`_numpy_tensors` is (quantized layers, training mode, a subclass)."""
    found = _numpy_tensors(net)
    if found is None:
        return None
    stem, layers, head, maps = _layout(*found, mirrored=net.config.symmetry == "mirror")
    with torch.no_grad():
        blocks = []
        for (g1, be1, m1, var1, eps1), lin1, (g2, be2, m2, var2, eps2), lin2 in layers:
            s1 = g1 / torch.sqrt(var1 + eps1)
            s2 = g2 / torch.sqrt(var2 + eps2)
            blocks.append((s1, be1 - m1 * s1, tuple(lin1[:-1]), s2, be2 + (lin1[-1] - m2) * s2, lin2))
        return [stem, blocks, head, maps]


def _coupled_folded(y: torch.Tensor, u: torch.Tensor, v: torch.Tensor, b: torch.Tensor | None = None
                    ) -> torch.Tensor:
    """:func:`couple_streams` of :class:`MirrorCoupledLinear` for rows ``[h0; h1]``, written into one array."""
    n = y.shape[0] // 2
    h0, h1 = y[:n], y[n:]
    us = torch.mm(h0 + h1, u.t()) if b is None else torch.addmm(b, h0 + h1, u.t())
    vd = torch.mm(h0 - h1, v.t())
    out = torch.empty_like(y)
    torch.add(us, vd, out=out[:n])
    torch.sub(us, vd, out=out[n:])
    return out


def forward_folded(net: PoseLifterNet, features: torch.Tensor) -> torch.Tensor | None:
    """:meth:`PoseLifterNet.forward` in eval mode for a batch: features ``(B, F)`` float32 -> standardized
    outputs ``(B, 49)``. Runs in slices of :data:`FOLDED_ROWS` rows, each BatchNorm applied as one
    multiply-add (with the hidden layer's bias before it), and no Dropout or concatenation passes over the
    activations. The same function as the module up to float32 rounding (``tests/test_numpy_path.py``).
    Returns None when the network is not the plain float32 network of its config (quantized, in training
    mode): run the module then. Call it under ``torch.inference_mode()``."""
    if features.dtype != torch.float32 or features.ndim != 2:
        return None
    folded = _fold(net)
    if folded is None:
        return None
    (w0, b0), blocks, (wh, bh), maps = folded  # maps: in_perm, in_sign, out_perm, out_scale, out_offset
    out = torch.empty((features.shape[0], NUM_OUTPUTS), dtype=torch.float32, device=features.device)
    step = FOLDED_ROWS // 2 if maps else FOLDED_ROWS
    for s in range(0, features.shape[0], step):
        x = features[s:s + step]
        n = len(x)
        if maps:
            x = torch.cat([x, x[:, maps[0]] * maps[1]])  # the features and the mirrored features
        h = torch.addmm(b0, x, w0.t())
        for s1, c1, lin1, s2, c2, lin2 in blocks:
            y = torch.addcmul(c1, h, s1).relu_()
            y = _coupled_folded(y, *lin1) if maps else torch.mm(y, lin1[0].t())
            y = torch.addcmul(c2, y, s2).relu_()
            h = (h + _coupled_folded(y, *lin2)) if maps else torch.addmm(lin2[1], y, lin2[0].t()).add_(h)
        g = torch.addmm(bh, h, wh.t())
        if maps:
            g0, g1 = g.chunk(2)
            g = 0.5 * (g0 + g1[:, maps[2]] * maps[3] + maps[4])  # the second stream's output mirrored back
        out[s:s + n] = g
    return out


def _forward_numpy_mirror(v: list[np.ndarray], eps: list[float], features: np.ndarray) -> np.ndarray:
    """A ``symmetry="mirror"`` network on a few rows of features ``(R, F)``: the two streams are the rows of a
    ``(2R, W)`` array (stream 0's rows, then stream 1's); each coupled layer is ``U`` on the streams' sum and
    ``V`` on their difference (:class:`MirrorCoupledLinear`), each weight read once for all ``R`` rows
    (:func:`_matvec_rows`)."""
    (w0, b0), blocks, (wh, bh), (in_perm, in_sign, out_perm, out_scale, out_offset) = _layout(v, eps, True)
    r = len(features)
    x = np.concatenate([features, features[:, in_perm] * in_sign])
    h = _product(w0, x) + b0

    def coupled(y: np.ndarray, u: np.ndarray, w: np.ndarray, b: np.ndarray) -> np.ndarray:
        y0, y1 = y[:r], y[r:]
        us = _matvec_rows(u, y0 + y1) + b
        vd = _matvec_rows(w, y0 - y1)
        return np.concatenate([us + vd, us - vd])

    for bn1, lin1, bn2, lin2 in blocks:
        s1, c1 = _bn_affine_np(bn1)
        s2, c2 = _bn_affine_np(bn2)
        y = np.maximum(h * s1 + c1, 0.0)
        y = np.maximum(coupled(y, *lin1) * s2 + c2, 0.0)
        h = h + coupled(y, *lin2)
    g = _product(wh, h) + bh
    return 0.5 * (g[:r] + g[r:, out_perm] * out_scale + out_offset)
