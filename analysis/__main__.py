"""Command line: ``python -m analysis build-model …`` and ``python -m analysis analyse …``."""

from analysis.pipeline.cli import main

raise SystemExit(main())
