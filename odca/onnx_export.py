"""``racf odca export``: ODCA for the car itself, as ONNX files onnxruntime runs without PyTorch.

ONNX, not TorchScript: a TorchScript file needs libtorch on the car (hundreds of MB, and the
Python process around it), while onnxruntime is a small, stable C/C++ runtime with Python, C
and C++ bindings, built for embedded targets (ARM included, as on the QCar 2's Jetson), and on
this machine it runs the prior in about a third of the time (``racf bench odca-onboard``).

What is exported:

- the prior (``prior.onnx``): the frozen Chronos-2 model's quantile forecast for one window of
  ``context_length`` depths over the horizon's patches, at the online module's batch of one;
- the delta head (``head.onnx``): its 917 parameters, features -> Delta;
- the gate and the kinematic branch are not networks but a few dozen comparisons on numbers:
  they run as they are (numpy) from the checkpoint's ``odca.json``, copied beside the models.

Chronos-2 builds its group attention mask with an ``einsum`` over booleans, which ONNX's
``Einsum`` does not take: the export runs it on 0/1 floats instead (the same products, hence
the same mask), patched for the export only.
"""

from __future__ import annotations

import hashlib
import json
import shutil
import warnings
from contextlib import contextmanager
from pathlib import Path
from typing import Iterator

import numpy as np

from racf.errors import UserError
from racf.odca.onnx_runtime import EXPORT_FILE, HEAD_FILE, PRIOR_FILE

__all__ = ["export_onnx", "OPSET"]

OPSET = 18


@contextmanager
def _float_group_mask() -> Iterator[None]:
    """Chronos-2's group-time mask built from 0/1 floats (ONNX's Einsum takes no booleans)."""
    import torch
    from chronos.chronos2.model import Chronos2Encoder
    from einops import rearrange

    original = Chronos2Encoder.__dict__["_construct_and_invert_group_time_mask"]

    def float_mask(group_ids, attention_mask, floating_type):
        group_mask = (group_ids[:, None] == group_ids[None, :]).to(floating_type)
        mask = torch.einsum("qb, bt -> qbt", group_mask, attention_mask.to(floating_type))
        mask = rearrange(mask, "q b t -> t 1 q b")
        return (1.0 - mask) * torch.finfo(floating_type).min

    Chronos2Encoder._construct_and_invert_group_time_mask = staticmethod(float_mask)
    try:
        yield
    finally:
        Chronos2Encoder._construct_and_invert_group_time_mask = original


def _export(module, args: tuple, path: Path, inputs: list[str], outputs: list[str]) -> None:
    import io
    import logging
    from contextlib import redirect_stdout

    import torch

    with warnings.catch_warnings(), redirect_stdout(io.StringIO()):
        warnings.simplefilter("ignore")
        logging.getLogger("torch.onnx").setLevel(logging.ERROR)
        program = torch.onnx.export(module.eval(), args, dynamo=True, input_names=inputs, output_names=outputs,
                                    opset_version=OPSET, verbose=False)
        program.save(str(path))


def _head_module(head):
    import torch

    from racf.odca.head import make_head

    module = make_head()
    module.load_state_dict({k: torch.as_tensor(np.asarray(v), dtype=torch.float32) for k, v in head.a.items()})
    return module


def _sha(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()[:16]


def export_onnx(out: str | Path, checkpoint: str | Path | None = None) -> dict:
    """Exports the ODCA checkpoint (default: the shipped one) to ``out``: ``prior.onnx``,
    ``head.onnx``, its ``odca.json`` and ``head.npz``, and ``export.json`` (what was exported,
    from what, with which versions). Returns the manifest."""
    import torch

    from racf.odca.features import FEATURE_NAMES
    from racf.odca.online import ODCA, SHIPPED_HEAD
    from racf.odca.prior import Chronos2Prior

    source = Path(checkpoint) if checkpoint is not None else SHIPPED_HEAD
    model = ODCA.load(source)
    if not isinstance(model.prior, Chronos2Prior):
        raise UserError(f"the checkpoint at {source} has no Chronos-2 prior to export")
    out = Path(out)
    if out.exists() and any(out.iterdir()):
        raise UserError(f"{out} exists and is not empty; choose another folder")
    out.mkdir(parents=True, exist_ok=True)
    cfg = model.config
    prior = model.prior
    patch = int(prior.pipeline.model_output_patch_size)
    n_patches = -(-cfg.horizon // patch)
    with _float_group_mask():
        _export(prior.quantile_module(n_patches), (torch.zeros(1, prior.context_length), torch.arange(1)),
                out / PRIOR_FILE, ["context", "group_ids"], ["quantiles"])
    _export(_head_module(model.head), (torch.zeros(1, len(FEATURE_NAMES)),), out / HEAD_FILE, ["features"], ["delta"])
    for name in ("odca.json", "head.npz"):
        shutil.copyfile(source / name, out / name)
    import onnx

    shipped = source.resolve() == SHIPPED_HEAD.resolve()
    manifest = {"format": "onnx", "opset": OPSET, "source": "shipped" if shipped else str(source),
                "source_sha": {name: _sha(source / name) for name in ("odca.json", "head.npz")},
                "prior": {"file": PRIOR_FILE, "context_length": int(prior.context_length), "batch": 1,
                          "output_patches": n_patches, "patch": patch,
                          "quantiles": [float(q) for q in prior.quantiles], "sha": _sha(out / PRIOR_FILE),
                          "n_parameters": int(sum(p.numel() for p in prior.model.parameters())),
                          "checkpoint": cfg.prior},
                "head": {"file": HEAD_FILE, "features": list(FEATURE_NAMES), "sha": _sha(out / HEAD_FILE),
                         "n_parameters": model.head.n_parameters},
                "gate": "numpy, from odca.json (a rule, not a network)",
                "versions": {"torch": torch.__version__, "onnx": onnx.__version__}}
    (out / EXPORT_FILE).write_text(json.dumps(manifest, indent=1) + "\n")
    return manifest
