"""``python -m study`` (``make study``): the study's command line."""
import sys

from study.driver import main

sys.exit(main())
