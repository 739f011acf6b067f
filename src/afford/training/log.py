"""Training logs: TensorBoard event files, a JSON-lines record, and a PNG of the curves."""

from __future__ import annotations

import json
from pathlib import Path


class RunLog:
    """Scalars by step, to TensorBoard (`tensorboard --logdir RUN`) and RUN/log.jsonl."""

    def __init__(self, run: Path):
        from torch.utils.tensorboard import SummaryWriter

        self.run = run
        self.path = run / "log.jsonl"
        self.writer = SummaryWriter(str(run / "tensorboard"))

    def add(self, step: int, values: dict[str, float]) -> None:
        for k, v in values.items():
            self.writer.add_scalar(k, v, step)
        with open(self.path, "a") as f:
            f.write(json.dumps({"step": step, **{k: round(float(v), 6) for k, v in values.items()}}) + "\n")

    def records(self) -> list[dict]:
        if not self.path.exists():
            return []
        return [json.loads(line) for line in self.path.read_text().splitlines() if line.strip()]

    def truncate_after(self, step: int) -> None:
        """Forget records past `step`: a resumed run repeats those steps."""
        kept = [r for r in self.records() if r["step"] <= step]
        self.path.write_text("".join(json.dumps(r) + "\n" for r in kept))

    def plot(self, title: str) -> Path:
        """curves.png: one panel per group of scalars ('train/...', 'val/...')."""
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        records = self.records()
        keys = sorted({k for r in records for k in r if k != "step"})
        groups: dict[str, list[str]] = {}
        for k in keys:
            groups.setdefault(k.split("/")[0], []).append(k)
        fig, axes = plt.subplots(
            1, max(len(groups), 1), figsize=(5 * max(len(groups), 1), 3.6), squeeze=False
        )
        for ax, (group, names) in zip(axes[0], groups.items(), strict=False):
            for name in names:
                pts = [(r["step"], r[name]) for r in records if name in r]
                ax.plot([p[0] for p in pts], [p[1] for p in pts], label=name.split("/", 1)[-1])
            ax.set_title(group)
            ax.set_xlabel("step")
            if group == "train":
                ax.set_yscale("log")
            ax.legend(fontsize=7)
            ax.grid(alpha=0.3)
        fig.suptitle(title)
        fig.tight_layout()
        out = self.run / "curves.png"
        fig.savefig(out, dpi=100)
        plt.close(fig)
        return out

    def close(self) -> None:
        self.writer.close()


class NullLog:
    """The log of a rank that does not write (every rank but 0 under torchrun)."""

    def add(self, step: int, values: dict[str, float]) -> None:
        pass

    def truncate_after(self, step: int) -> None:
        pass

    def plot(self, title: str) -> None:
        pass

    def close(self) -> None:
        pass
