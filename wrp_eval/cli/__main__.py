"""``python -m wrp_eval.cli``: the same as the ``wrp-eval`` script."""

import sys

from wrp_eval.cli import main

sys.exit(main())
