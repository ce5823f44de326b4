"""Write the stage diagram of docs/ARCHITECTURE.md from the pipeline's own list of its stages
(`analysis.pipeline.stage_order.ORDER`), between the markers ``<!-- stages:start -->`` and
``<!-- stages:end -->``, so the page never states another order than the one the code runs.

Run from the repository root: `python docs/stage_diagram.py` rewrites the page; ``--check`` only
says whether it is up to date (exit 1 when not); ``--print`` prints the diagram.
`tests/test_architecture_stages.py` fails while the page differs from the list.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

DOCS = Path(__file__).resolve().parent
ARCHITECTURE = DOCS / "ARCHITECTURE.md"
START, END = "<!-- stages:start -->", "<!-- stages:end -->"
UNFIT_MARK = "*"

if str(DOCS.parent) not in sys.path:  # run as a script from anywhere: the checkout's analysis
    sys.path.insert(0, str(DOCS.parent))

from analysis.pipeline.stage_order import ORDER, Stage  # noqa: E402 (needs the path above)


def diagram(order: tuple[Stage, ...] = ORDER) -> str:
    """The stages top to bottom: timing key, what the progress bar says, the module doing it;
    after the fit check, which stages still run for a recording that is not the exercise."""
    keys = [stage.key + (f" {UNFIT_MARK}" if stage.if_unfit else "") for stage in order]
    key_width = max(len(key) for key in keys) + 2
    label_width = max(len(stage.label) for stage in order) + 2
    lines = ["   " + "stage".ljust(key_width) + "progress bar".ljust(label_width) + "done by"]
    for k, (key, stage) in enumerate(zip(keys, order, strict=True)):
        arrow = "   " if k == 0 else "─► "
        lines.append(arrow + key.ljust(key_width) + stage.label.ljust(label_width) + stage.done_by)
        if stage.key == "match":
            lines.append(
                f" │   not the exercise: only the stages marked {UNFIT_MARK} follow "
                "(no repetition, no score)"
            )
    return "\n".join(["```", *lines, "```"])


def refreshed(page: str, order: tuple[Stage, ...] = ORDER) -> str:
    """The page with the text between its stage markers replaced by the diagram."""
    before, start, rest = page.partition(START)
    _, end, after = rest.partition(END)
    if not start or not end:
        raise ValueError(f"the page has no {START} ... {END} markers")
    return f"{before}{START}\n{diagram(order)}\n{END}{after}"


def main(argv: list[str] | None = None) -> int:
    options = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    options.add_argument("--check", action="store_true", help="exit 1 when the page is stale")
    options.add_argument("--print", action="store_true", help="print the diagram only")
    args = options.parse_args(argv)
    if args.print:
        print(diagram())
        return 0
    page = ARCHITECTURE.read_text()
    new = refreshed(page)
    if args.check:
        print("up to date" if new == page else "stale: run python docs/stage_diagram.py")
        return 0 if new == page else 1
    ARCHITECTURE.write_text(new)
    return 0


if __name__ == "__main__":
    sys.exit(main())
