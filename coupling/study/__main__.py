"""``python -m coupling.study``: the same as ``fembem study``."""
import sys

from coupling.study.driver import main

sys.exit(main())
