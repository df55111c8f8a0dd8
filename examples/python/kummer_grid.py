#!/usr/bin/env python3
"""The Kummer family F_mu = 0 as mu moves through its nodes' life: ray-traced pictures and the
floaters that follow the moving surface, in a grid of pictures (matplotlib).

Usage: kummer_grid.py [OUT.png]   (default kummer_grid.png; PYTHONPATH=BUILD/python)
"""
import sys

import numpy as np

import zeroset


def main() -> int:
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("kummer_grid: matplotlib is not installed (apt-get install python3-matplotlib); "
              "nothing to draw")
        return 0
    out = sys.argv[1] if len(sys.argv) > 1 else "kummer_grid.png"
    values = np.linspace(0.6, 2.6, 6)
    s = zeroset.Surface("kummer", mu=values[0])
    floaters = s.sample(max_count=1500, seed=1)    # settled at the first value
    fig, axes = plt.subplots(2, len(values), figsize=(2.2 * len(values), 4.6))
    for k, mu in enumerate(values):
        s.params["mu"] = mu
        if k > 0:
            floaters.step(40, params={"mu": mu})   # the floaters follow mu over 40 steps
        axes[0, k].imshow(s.render(size=(240, 240)))
        axes[1, k].imshow(floaters.render(size=(240, 240)))
        axes[0, k].set_title(f"mu = {mu:.2f}")
        for ax in axes[:, k]:
            ax.axis("off")
    axes[0, 0].text(-20, 120, "ray traced", rotation=90, va="center")
    axes[1, 0].text(-20, 120, "floaters", rotation=90, va="center")
    fig.tight_layout()
    fig.savefig(out, dpi=100)
    print(f"wrote {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
