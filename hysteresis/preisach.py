"""Placeholder: the Preisach model is being written (see issue 2)."""


class PreisachModel:  # pragma: no cover - replaced by the real implementation
    @classmethod
    def from_relays(cls, alpha, beta, weights=None):
        raise NotImplementedError("PreisachModel is not implemented yet")
