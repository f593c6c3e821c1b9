"""``python -m analysis.cli``: the ``hyst`` command line."""

import sys

from analysis.cli import main

if __name__ == "__main__":  # guarded: importing this module (e.g. by autodoc) runs nothing
    sys.exit(main())
