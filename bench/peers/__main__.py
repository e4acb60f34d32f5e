"""``python -m bench.peers``: the peer benchmark (see :mod:`bench.peers`)."""
import sys

from bench.peers.cli import main

sys.exit(main())
