"""FORC measurements shipped with the toolkit (package data), for tutorials and trials.

    from analysis.identification.datasets import forc_sample
    from analysis.identification.forc_io import read_forc_file

    data = read_forc_file(forc_sample("micromag-synthetic"), drift_correction="multiplicative")

:data:`FORC_SAMPLES` names them: a synthetic MicroMag export of a known sample and four real
instrument exports (Lake Shore 8600 CSV, MicroMag remanence, irregular and data-only files; MIT
licensed, from pyFORC — see ``sample_data/README.md``).
"""

from __future__ import annotations

from importlib import resources
from pathlib import Path

__all__ = ["FORC_SAMPLES", "forc_sample"]

#: name -> (file in ``analysis/identification/sample_data``, what it is)
FORC_SAMPLES: dict[str, tuple[str, str]] = {
    "micromag-synthetic": (
        "forc_micromag_0016_hybrid_si.frc",
        "synthetic MicroMag Series 0016 export, 46 curves, B_c ~ N(30, 6²) mT",
    ),
    "micromag-remanence-synthetic": (
        "forc_micromag_remanence.frc",
        "synthetic MicroMag remanence FORC script export of a 400-relay model",
    ),
    "lakeshore-8600": (
        "B-9-3-85-87-FORC-1.5T_excerpt.csv",
        "Lake Shore 8600 FORC CSV (real, excerpt of 28 curves)",
    ),
    "micromag-remanence": (
        "MSM33-60-1-d416_2.remforc",
        "MicroMag remanence FORC script export (real)",
    ),
    "micromag-irregular": (
        "MSM33-60-1-d416_2.irforc",
        "MicroMag irregular in-field FORC script export (real)",
    ),
    "micromag-data-only": (
        "ps97-085-3-d472_9.irforc",
        "irregular FORC export saved as its data section alone (real)",
    ),
}


def forc_sample(name: str) -> Path:
    """The path of the shipped FORC file ``name`` (one of :data:`FORC_SAMPLES`)."""
    if name not in FORC_SAMPLES:
        raise ValueError(f"name must be one of {', '.join(FORC_SAMPLES)}, got {name!r}")
    path = resources.files("analysis.identification") / "sample_data" / FORC_SAMPLES[name][0]
    return Path(str(path))
