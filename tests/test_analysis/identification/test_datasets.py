"""The FORC files shipped as package data: present, the same bytes as the test copies, and
read by the readers (so the README and the tutorials work on a normal install)."""

from __future__ import annotations

import pytest
from support_paths import DATA

from analysis.identification.datasets import FORC_SAMPLES, forc_sample
from analysis.identification.forc_io import read_forc_file


@pytest.mark.parametrize("name", list(FORC_SAMPLES))
def test_every_sample_is_shipped_and_reads(name):
    path = forc_sample(name)
    assert path.is_file()
    copies = [DATA / path.name, DATA / "forc_public" / path.name]
    assert any(c.is_file() and c.read_bytes() == path.read_bytes() for c in copies)
    data = read_forc_file(path)
    assert data.curves.n_curves >= 16  # the smallest: the 16-curve synthetic remanence file


def test_unknown_name_is_refused_with_the_names():
    with pytest.raises(ValueError, match="micromag-synthetic"):
        forc_sample("nope")
