"""The agreement model: how well a clause describes a state (paper V's proposal, our design).

Paper V proposes replacing eq. (5)'s image comparison with "a neural network that quantifies
agreement between predicted outcomes and sentences describing goals", e.g. CLIP. With no
pretrained model within reach and scenes this simple, this one is small and trained on the
simulator's states, where every clause's truth is known (`words/facts.py`).

A clause is first read into its parts (`sentences.read_clause`: a relation, the subject's noun
phrase, the other argument, negated or not), and the model follows that structure: a
convolution stem reads the RGBD state down to a 16x16 grid of features, with the grid's
coordinates as two more channels; a GRU encodes each noun phrase into a query that attends
over the grid, giving what is found (features), where (the attention-weighted coordinates) and
how surely (the best match's score, low when the object is gone); a head reads both objects'
findings with the relation's embedding and gives the logit that the clause holds, negated by
its sign for a negated clause. A statement holds when all its clauses do: its score is the sum
of their log-probabilities.
"""

from __future__ import annotations

import torch
from torch import nn

from afford.words.config import AgreementConfig
from afford.words.sentences import SentenceError, clause_texts, read_clause, tokens


def coordinates(x: torch.Tensor) -> torch.Tensor:
    """x (B, C, H, W) with two channels more: column and row in [-1, 1]."""
    b, _, h, w = x.shape
    cols = torch.linspace(-1, 1, w, device=x.device, dtype=x.dtype).expand(b, 1, h, w)
    rows = torch.linspace(-1, 1, h, device=x.device, dtype=x.dtype)[:, None].expand(b, 1, h, w)
    return torch.cat([x, cols, rows], 1)


class Residual(nn.Module):
    def __init__(self, width: int):
        super().__init__()
        self.body = nn.Sequential(
            nn.Conv2d(width + 2, width, 3, padding=1), nn.GELU(), nn.Conv2d(width, width, 3, padding=1)
        )

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return x + self.body(coordinates(x))


class AgreementNet(nn.Module):
    def __init__(self, config: AgreementConfig):
        super().__init__()
        if not config.vocabulary or not config.relations:
            raise ValueError("an agreement model needs its vocabulary and relations in its config")
        self.config = config
        self.vocabulary = config.vocabulary
        self.ids = {w: i + 1 for i, w in enumerate(self.vocabulary)}  # 0 pads
        self.relation_ids = {r: i for i, r in enumerate(config.relations)}
        self.embed = nn.Embedding(len(self.vocabulary) + 1, config.embed, padding_idx=0)
        self.phrase = nn.GRU(config.embed, config.text, batch_first=True)
        layers, c = [], config.in_channels + 2
        for out in config.stem:
            layers += [nn.Conv2d(c, out, 3, stride=2, padding=1), nn.GELU()]
            c = out
        layers += [nn.Conv2d(c, config.width, 1)]
        self.stem = nn.Sequential(*layers)
        self.blocks = nn.Sequential(*(Residual(config.width) for _ in range(config.blocks)))
        self.keys = nn.Conv2d(config.width + 2, config.text, 1)
        self.relation = nn.Embedding(len(config.relations), config.text)
        found = config.width + 3  # features, x, y, match score
        self.head = nn.Sequential(
            nn.Linear(2 * found + 2 + 2 * config.text, config.head),
            nn.GELU(),
            nn.Linear(config.head, config.head),
            nn.GELU(),
            nn.Linear(config.head, 1),
        )

    # ------------------------------------------------------------------ reading clauses
    def _ids(self, phrases: list[str]) -> torch.Tensor:
        rows = [[self.ids[w] for w in tokens(p)] for p in phrases]
        out = torch.zeros((len(rows), max(1, max(len(r) for r in rows))), dtype=torch.long)
        for i, r in enumerate(rows):
            out[i, : len(r)] = torch.tensor(r, dtype=torch.long)
        return out

    def encode(self, clauses: list[str]) -> dict[str, torch.Tensor]:
        """The model's input for normalised clauses: word ids of each subject and other phrase,
        relation ids, negation signs. A word or clause it cannot read is a SentenceError."""
        for clause in clauses:
            unknown = [w for w in tokens(clause) if w not in self.ids]
            if unknown:
                raise SentenceError(
                    f"unknown word {unknown[0]!r}; the words known are: {', '.join(self.vocabulary)}"
                )
        parts = [read_clause(" ".join(tokens(c))) for c in clauses]
        return {
            "subject": self._ids([p.subject for p in parts]),
            "other": self._ids([p.other for p in parts]),
            "relation": torch.tensor([self.relation_ids[p.relation] for p in parts]),
            "sign": torch.tensor([-1.0 if p.negated else 1.0 for p in parts]),
        }

    def _phrase(self, ids: torch.Tensor) -> torch.Tensor:
        lengths = (ids > 0).sum(1).clamp_min(1).cpu()
        packed = nn.utils.rnn.pack_padded_sequence(
            self.embed(ids), lengths, batch_first=True, enforce_sorted=False
        )
        _, h = self.phrase(packed)
        return h[-1] * (ids > 0).any(1, keepdim=True)  # an empty phrase (no other argument): zeros

    # ------------------------------------------------------------------ scoring
    def _find(self, grid: torch.Tensor, keys: torch.Tensor, query: torch.Tensor) -> torch.Tensor:
        """Attend over the grid with a phrase's query: (B, features + x + y + best score)."""
        scores = torch.einsum("bchw,bc->bhw", keys, query).flatten(1) / keys.shape[1] ** 0.5
        weights = scores.softmax(1)
        feats = torch.einsum("bn,bcn->bc", weights, grid.flatten(2))
        xy = torch.einsum("bn,bcn->bc", weights, coordinates(grid)[:, -2:].flatten(2))
        return torch.cat([feats, xy, scores.amax(1, keepdim=True)], 1)

    def forward(self, images: torch.Tensor, clauses: dict[str, torch.Tensor]) -> torch.Tensor:
        """Logits (B,) that clause b (`encode`d) holds in image b (B, C, H, W)."""
        grid = self.blocks(self.stem(coordinates(images)))
        keys = self.keys(coordinates(grid))
        subject, other = self._phrase(clauses["subject"]), self._phrase(clauses["other"])
        a, b = self._find(grid, keys, subject), self._find(grid, keys, other)
        rel = self.relation(clauses["relation"])
        x = torch.cat([a, b, a[:, -3:-1] - b[:, -3:-1], rel, other], 1)
        return self.head(x)[:, 0] * clauses["sign"].to(x.dtype)

    def statement_logprob(self, images: torch.Tensor, statement: str) -> torch.Tensor:
        """(B,) log-probability that every clause of `statement` holds in each image
        (differentiable in the images)."""
        parts = clause_texts(statement)
        encoded = self.encode(parts)
        total = images.new_zeros(len(images))
        for c in range(len(parts)):
            one = {
                k: v[c : c + 1].expand(len(images), *v.shape[1:]).to(images.device)
                for k, v in encoded.items()
            }
            total = total + nn.functional.logsigmoid(self(images, one))
        return total
