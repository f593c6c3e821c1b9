"""FORC file formats, one module per format: ``csv_format`` (three-column CSV), ``micromag``
(MicroMag FORC text export), ``segments`` (MicroMag "Multiple segments" exports of irregular
FORC protocols; ``remanence`` reconstructs the remanence FORC scripts among them), ``blocks``
(data-only two-column files) and ``lakeshore`` (Lake Shore 8600 FORC CSV), plus the parsing
they share (``common``: the data set type, decoding, calibration points, drift correction).

Read files through :mod:`analysis.identification.forc_io` (format detection, one entry point).
"""
