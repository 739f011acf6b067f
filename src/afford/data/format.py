"""The on-disk dataset: a manifest plus compressed shards of whole sequences (paper III.B).

Why this format. A shard is one NumPy ``.npz`` (deflate-compressed zip) holding a fixed run of
sequence indices, so that
- a parallel worker writes a whole shard alone, to a temporary name, then renames it into
  place: the rename is atomic, so a shard is there whole or not at all (crash-safe);
- a re-run finds which shards exist and makes only the missing ones (resumable);
- the content of sequence i depends only on (seed, i), never on which worker made it or in
  what order (deterministic);
- the zip's CRCs catch a corrupt or truncated shard, and a reader names the shard that is bad;
- a shard's arrays load in one go, and the whole train split of the `cpu` dataset fits in
  memory, so training reads at random with no further I/O.

Layout of DIR: ``dataset.json`` (format version, size, seed, splits) and
``shards/shard-NNNNNN.npz``. Images are stored as uint8 RGB and uint16 depth (depth in [0, 1]
quantised to 1/65535): exact for RGB, below the renderer's precision for depth.
"""

from __future__ import annotations

import json
import os
import zipfile
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np

from afford.errors import UserError
from afford.sim.affordance import AFF_WIDTH, Affordance, decode_affordance

FORMAT = "afford-sequences"
FORMAT_VERSION = 1
MANIFEST = "dataset.json"
SHARD_DIR = "shards"
DEPTH_SCALE = 65535
# The authors' release: 26,563 sequences of which 500 validation and 500 test.
PAPER_SEQUENCES = 26_563
PAPER_HELD_OUT = 500
POSE_COLUMNS = ("x", "y", "z", "qw", "qx", "qy", "qz")
SPLITS = ("train", "val", "test")


class DataError(UserError):
    """A dataset that cannot be read: missing, corrupt, or of another format version."""


@dataclass
class Sequence:
    """One generated sequence: T states and the T-1 affordances executed between them.

    rgb (T, H, W, 3) uint8; depth (T, H, W) uint16; affordances: per state an (n, 7) float32
    array of AFF_COLUMNS (the ground-truth list); actions (T-1, 7) the executed ones;
    held (T,) int8 slot index of the held object or -1; poses (T, slots, 7) float32 true poses
    (NaN for a slot not on the table); slots: the object slot names; arm_paths (T-1, 32, 5) the
    arm's key points during each execution (`sim/arm_path.py`; None in datasets made before they
    were recorded). A pose-only dataset (`afford generate --poses-only`) stores images of size 0.
    """

    index: int
    rgb: np.ndarray
    depth: np.ndarray
    affordances: list[np.ndarray]
    actions: np.ndarray
    held: np.ndarray
    poses: np.ndarray
    slots: tuple[str, ...]
    arm_paths: np.ndarray | None = None
    masks: np.ndarray | None = None  # (T, H, W) int8 slot seen per pixel, -1 none (`--masks`)

    @property
    def has_images(self) -> bool:
        return self.rgb.shape[1] > 0

    @property
    def length(self) -> int:
        """Number of executions."""
        return len(self.actions)

    def image(self, t: int) -> np.ndarray:
        """State t as the (H, W, 4) float32 RGBD image the nets and the planner use."""
        if not self.has_images:
            raise DataError(
                f"sequence {self.index} has no images: its dataset holds poses only "
                "(`afford generate --poses-only`); use a dataset made with images"
            )
        return dequantise(self.rgb[t], self.depth[t])

    def action(self, t: int) -> Affordance:
        return decode_affordance(self.actions[t])

    def affordance_list(self, t: int) -> list[Affordance]:
        return [decode_affordance(r) for r in self.affordances[t]]


def dequantise(rgb: np.ndarray, depth: np.ndarray) -> np.ndarray:
    """uint8 RGB (H, W, 3) and uint16 depth (H, W) -> (H, W, 4) float32 RGBD in [0, 1]."""
    return np.concatenate(
        [rgb.astype(np.float32) / 255.0, depth[..., None].astype(np.float32) / DEPTH_SCALE], axis=-1
    )


def quantise(image: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(H, W, 4) float RGBD in [0, 1] -> uint8 RGB, uint16 depth."""
    rgb = np.round(np.clip(image[..., :3], 0, 1) * 255).astype(np.uint8)
    depth = np.round(np.clip(image[..., 3], 0, 1) * DEPTH_SCALE).astype(np.uint16)
    return rgb, depth


# ---------------------------------------------------------------------------- manifest
@dataclass
class Manifest:
    sequences: int
    seed: int
    shard_size: int
    max_steps: int
    slots: list[str]
    splits: dict[str, list[int]] = field(default_factory=dict)  # name -> [start, stop) of indices
    format: str = FORMAT
    version: int = FORMAT_VERSION
    generator: dict = field(default_factory=dict)  # free-form: layout config, package version

    @property
    def n_shards(self) -> int:
        return -(-self.sequences // self.shard_size)

    def shard_range(self, shard: int) -> range:
        return range(shard * self.shard_size, min((shard + 1) * self.shard_size, self.sequences))

    def split_of(self, index: int) -> str:
        for name, (start, stop) in self.splits.items():
            if start <= index < stop:
                return name
        raise IndexError(index)


def default_splits(n: int, of: int | None = None) -> dict[str, list[int]]:
    """val and test held out in the paper's proportion (500 each of 26,563), at least 1 each.

    With `of`, the val and test splits are those of an `of`-sequence dataset of the same seed,
    which shares the first sequences: a smaller dataset measured on the larger one's splits.
    """
    size = n if of is None else of
    held = max(1, round(size * PAPER_HELD_OUT / PAPER_SEQUENCES)) if size >= 3 else 0
    if 2 * held >= n and of is not None:
        raise DataError(f"the splits of {of} sequences hold out {2 * held}: more than {n} sequences")
    return {"val": [0, held], "test": [held, 2 * held], "train": [2 * held, n]}


def write_json_atomic(path: Path, obj: object) -> None:
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    tmp.write_text(json.dumps(obj, indent=2) + "\n")
    os.replace(tmp, path)


def write_manifest(root: Path, manifest: Manifest) -> None:
    root.mkdir(parents=True, exist_ok=True)
    write_json_atomic(root / MANIFEST, asdict(manifest))


def read_manifest(root: str | Path) -> Manifest:
    path = Path(root) / MANIFEST
    if not path.is_file():
        raise DataError(f"{root}: not a dataset (no {MANIFEST}); make one with `afford generate`")
    try:
        obj = json.loads(path.read_text())
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as e:
        raise DataError(f"{path}: unreadable manifest ({e})") from None
    if not isinstance(obj, dict) or obj.get("format") != FORMAT:
        raise DataError(f"{path}: not an afford dataset manifest")
    if obj.get("version") != FORMAT_VERSION:
        raise DataError(
            f"{path}: dataset format version {obj.get('version')!r}, this afford reads version "
            f"{FORMAT_VERSION}; regenerate it with this version's `afford generate`"
        )
    try:
        return Manifest(**obj)
    except TypeError as e:
        raise DataError(f"{path}: malformed manifest ({e})") from None


# ---------------------------------------------------------------------------- shards
def shard_path(root: Path, shard: int) -> Path:
    return Path(root) / SHARD_DIR / f"shard-{shard:06d}.npz"


def write_shard(path: Path, sequences: list[Sequence]) -> None:
    """Write sequences as one shard, atomically: a temporary file renamed into place."""
    lengths = np.array([len(s.rgb) for s in sequences], dtype=np.int32)
    aff_counts = np.array([len(a) for s in sequences for a in s.affordances], dtype=np.int32)
    arrays = {
        "index": np.array([s.index for s in sequences], dtype=np.int64),
        "state_count": lengths,
        "rgb": np.concatenate([s.rgb for s in sequences]),
        "depth": np.concatenate([s.depth for s in sequences]),
        "held": np.concatenate([s.held for s in sequences]).astype(np.int8),
        "poses": np.concatenate([s.poses for s in sequences]).astype(np.float32),
        "aff_count": aff_counts,
        "affordances": np.concatenate([a for s in sequences for a in s.affordances]).reshape(-1, AFF_WIDTH),
        "actions": np.concatenate([s.actions for s in sequences]).reshape(-1, AFF_WIDTH).astype(np.float32),
    }
    if all(s.masks is not None for s in sequences):
        arrays["masks"] = np.concatenate([s.masks for s in sequences]).astype(np.int8)
    if all(s.arm_paths is not None for s in sequences):
        arrays["arm_path"] = np.concatenate([s.arm_paths for s in sequences]).astype(np.float32)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    with open(tmp, "wb") as f:
        np.savez_compressed(f, **arrays)
        f.flush()
        os.fsync(f.fileno())
    os.replace(tmp, path)


def read_shard(path: Path, slots: tuple[str, ...]) -> list[Sequence]:
    """All sequences of one shard; DataError naming the shard if it is corrupt."""
    try:
        with np.load(path, allow_pickle=False) as z:
            a = {k: z[k] for k in z.files}
    except FileNotFoundError:
        raise DataError(f"{path}: shard missing") from None
    except (OSError, ValueError, EOFError, KeyError, zipfile.BadZipFile, zipfile.LargeZipFile) as e:
        raise DataError(f"{path}: corrupt shard ({type(e).__name__}: {e})") from None
    try:
        return _split_shard(a, slots)
    except (KeyError, ValueError, IndexError) as e:
        raise DataError(f"{path}: corrupt shard (inconsistent arrays: {e})") from None


def _split_shard(a: dict[str, np.ndarray], slots: tuple[str, ...]) -> list[Sequence]:
    counts = a["state_count"]
    n_states = int(counts.sum())
    n_exec = n_states - len(counts)
    aff_counts = a["aff_count"]
    for key, want in (("rgb", n_states), ("depth", n_states), ("held", n_states), ("poses", n_states)):
        if len(a[key]) != want:
            raise ValueError(f"{key} has {len(a[key])} rows, expected {want}")
    if len(aff_counts) != n_states or int(aff_counts.sum()) != len(a["affordances"]):
        raise ValueError("affordance counts do not add up")
    if len(a["actions"]) != n_exec or len(a["index"]) != len(counts):
        raise ValueError("executed-action rows do not add up")
    paths, masks = a.get("arm_path"), a.get("masks")
    if masks is not None and len(masks) != n_states:
        raise ValueError("mask rows do not add up")
    if paths is not None and len(paths) != n_exec:
        raise ValueError("arm path rows do not add up")
    state_start = np.concatenate([[0], np.cumsum(counts)])
    aff_start = np.concatenate([[0], np.cumsum(aff_counts)])
    out = []
    for k, index in enumerate(a["index"]):
        s0, s1 = state_start[k], state_start[k + 1]
        out.append(
            Sequence(
                index=int(index),
                rgb=a["rgb"][s0:s1],
                depth=a["depth"][s0:s1],
                affordances=[a["affordances"][aff_start[t] : aff_start[t + 1]] for t in range(s0, s1)],
                actions=a["actions"][s0 - k : s1 - k - 1],
                held=a["held"][s0:s1],
                poses=a["poses"][s0:s1],
                slots=slots,
                arm_paths=None if paths is None else paths[s0 - k : s1 - k - 1],
                masks=None if masks is None else masks[s0:s1],
            )
        )
    return out


def shard_status(root: Path, manifest: Manifest) -> tuple[list[int], list[int]]:
    """(present, missing) shard numbers, by file existence only (cheap)."""
    present, missing = [], []
    for k in range(manifest.n_shards):
        (present if shard_path(root, k).is_file() else missing).append(k)
    return present, missing


class Dataset:
    """Read access to a generated dataset: sequences by global index or by split.

    Shards load on first use and stay cached (`cache_shards` of them, all by default): the
    `cpu` dataset's train split fits in memory, and training then reads at random for free.
    """

    def __init__(self, root: str | Path, cache_shards: int | None = None):
        self.root = Path(root)
        self.manifest = read_manifest(self.root)
        self.slots = tuple(self.manifest.slots)
        self._cache: dict[int, list[Sequence]] = {}
        self._cache_limit = cache_shards

    def __len__(self) -> int:
        return self.manifest.sequences

    def indices(self, split: str | None = None) -> range:
        if split is None:
            return range(self.manifest.sequences)
        if split not in self.manifest.splits:
            raise DataError(f"{self.root}: no split {split!r}; it has {sorted(self.manifest.splits)}")
        start, stop = self.manifest.splits[split]
        return range(start, stop)

    def shard(self, k: int) -> list[Sequence]:
        if k not in self._cache:
            if self._cache_limit is not None and len(self._cache) >= self._cache_limit:
                self._cache.pop(next(iter(self._cache)))
            seqs = read_shard(shard_path(self.root, k), self.slots)
            expected = list(self.manifest.shard_range(k))
            if [s.index for s in seqs] != expected:
                raise DataError(f"{shard_path(self.root, k)}: corrupt shard (holds the wrong sequences)")
            if self.manifest.generator.get("masks", False) and any(s.masks is None for s in seqs):
                raise DataError(
                    f"{shard_path(self.root, k)}: corrupt shard (no instance masks in a dataset made with "
                    "--masks); re-run the same `afford generate` to make it again"
                )
            self._cache[k] = seqs
        return self._cache[k]

    def sequence(self, index: int) -> Sequence:
        if not 0 <= index < self.manifest.sequences:
            raise DataError(f"{self.root}: no sequence {index}; it has {self.manifest.sequences}")
        k, j = divmod(index, self.manifest.shard_size)
        return self.shard(k)[j]

    def sequences(self, split: str | None = None):
        for i in self.indices(split):
            yield self.sequence(i)


def shard_summary(path: Path) -> dict[str, np.ndarray]:
    """The small arrays of a shard (no images): what `afford data info` counts, and the true
    poses and held objects that effects are read from (data/effects.py)."""
    keys = ("index", "state_count", "aff_count", "affordances", "actions", "held", "poses")
    try:
        with np.load(path, allow_pickle=False) as z:
            out = {k: z[k] for k in keys}
            if "arm_path" in z.files:
                out["arm_path"] = z["arm_path"]
            return out
    except (OSError, ValueError, EOFError, KeyError, zipfile.BadZipFile) as e:
        raise DataError(f"{path}: corrupt shard ({type(e).__name__}: {e})") from None


def check_shard(root: Path, manifest: Manifest, k: int) -> str | None:
    """One line naming what is wrong with shard `k`, or None when it is whole: every zip member's
    CRC (the arrays are inflated, not decoded) and the sequence indices it holds."""
    path = shard_path(root, k)
    try:
        with zipfile.ZipFile(path) as z:
            bad = z.testzip()
            if bad is not None:
                return f"{path}: corrupt shard (checksum of {bad} fails)"
        with np.load(path, allow_pickle=False) as a:
            index = a["index"]
            lacks_masks = manifest.generator.get("masks", False) and "masks" not in a.files
    except FileNotFoundError:
        return f"{path}: shard missing"
    except (OSError, ValueError, EOFError, KeyError, zipfile.BadZipFile) as e:
        return f"{path}: corrupt shard ({type(e).__name__}: {e})"
    if index.tolist() != list(manifest.shard_range(k)):
        return f"{path}: corrupt shard (holds the wrong sequences)"
    if lacks_masks:  # written by a generator that did not keep them
        return f"{path}: corrupt shard (no instance masks in a dataset made with --masks)"
    return None


def verify(root: str | Path, progress: bool = False) -> tuple[list[str], int]:
    """Read every shard in full (zip CRCs, array consistency, sequence indices).

    Returns (problems, good shard count); a problem is one line naming a shard.
    """
    root = Path(root)
    manifest = read_manifest(root)
    from tqdm import tqdm

    problems, good = [], 0
    for k in tqdm(range(manifest.n_shards), desc="verify", unit="shard", disable=not progress, leave=False):
        path = shard_path(root, k)
        if not path.is_file():
            problems.append(f"{path}: shard missing (re-run the same `afford generate` to make it)")
            continue
        try:
            seqs = read_shard(path, tuple(manifest.slots))
            if [s.index for s in seqs] != list(manifest.shard_range(k)):
                raise DataError(f"{path}: corrupt shard (holds the wrong sequences)")
        except DataError as e:
            problems.append(str(e))
            continue
        good += 1
    return problems, good
