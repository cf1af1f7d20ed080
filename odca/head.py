"""The delta head: a tiny MLP predicting the additive depth correction Delta(t)."""

from __future__ import annotations

import numpy as np

from racf.odca.features import FEATURE_NAMES

__all__ = ["HEAD_HIDDEN", "make_head", "head_parameters", "HeadWeights"]

#: 10 features -> 32 -> 16 -> 1 with a learned input scale: 917 trainable parameters.
HEAD_HIDDEN = (32, 16)


def make_head():
    """The torch module (training only)."""
    import torch
    from torch import nn

    class DeltaHead(nn.Module):
        def __init__(self) -> None:
            super().__init__()
            n = len(FEATURE_NAMES)
            self.scale = nn.Parameter(torch.ones(n))
            self.shift = nn.Parameter(torch.zeros(n))
            self.net = nn.Sequential(nn.Linear(n, HEAD_HIDDEN[0]), nn.Tanh(), nn.Linear(*HEAD_HIDDEN), nn.Tanh(),
                                     nn.Linear(HEAD_HIDDEN[1], 1))

        def forward(self, x):
            return self.net(x * self.scale + self.shift).squeeze(-1)

    return DeltaHead()


def head_parameters(module) -> int:
    return sum(p.numel() for p in module.parameters() if p.requires_grad)


class HeadWeights:
    """The trained head for inference in numpy, row by row (identical numbers for 1 or N rows)."""

    NAMES = ("scale", "shift", "net.0.weight", "net.0.bias", "net.2.weight", "net.2.bias", "net.4.weight",
             "net.4.bias")

    def __init__(self, arrays: dict[str, np.ndarray]) -> None:
        missing = [k for k in self.NAMES if k not in arrays]
        if missing:
            raise ValueError(f"head weights lack {missing}")
        self.a = {k: np.asarray(arrays[k], float) for k in self.NAMES}
        n = len(FEATURE_NAMES)
        shapes = {"scale": (n,), "shift": (n,), "net.0.weight": (HEAD_HIDDEN[0], n), "net.0.bias": (HEAD_HIDDEN[0],),
                  "net.2.weight": (HEAD_HIDDEN[1], HEAD_HIDDEN[0]), "net.2.bias": (HEAD_HIDDEN[1],),
                  "net.4.weight": (1, HEAD_HIDDEN[1]), "net.4.bias": (1,)}
        for k, shape in shapes.items():
            if self.a[k].shape != shape:
                raise ValueError(f"head weight {k} has shape {self.a[k].shape}, expected {shape}")

    @classmethod
    def from_module(cls, module) -> "HeadWeights":
        return cls({k: v.detach().cpu().numpy() for k, v in module.state_dict().items()})

    @property
    def n_parameters(self) -> int:
        return int(sum(v.size for v in self.a.values()))

    def __call__(self, x: np.ndarray) -> np.ndarray:
        """(N, 10) features -> (N,) Delta. Elementwise products and fixed-order sums, no BLAS."""
        a = self.a
        h = x * a["scale"] + a["shift"]
        h = np.tanh((h[:, None, :] * a["net.0.weight"][None]).sum(-1) + a["net.0.bias"])
        h = np.tanh((h[:, None, :] * a["net.2.weight"][None]).sum(-1) + a["net.2.bias"])
        return (h[:, None, :] * a["net.4.weight"][None]).sum(-1)[:, 0] + a["net.4.bias"][0]
