"""``python -m ngfrac``: the command line."""
import sys

from .cli import main

if __name__ == "__main__":  # importing the module (autosummary does) runs nothing
    sys.exit(main())
