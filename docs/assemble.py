"""Assemble docs/PERFORMANCE.md, EVALUATION.md and RELIABILITY.md from docs/sections/.

Each benchmark or evaluation script writes (or its author updates) one section file; this script
puts them in a fixed order under a short introduction so the published documents never drift from
the sections. Run from the repository root: `python docs/assemble.py`.
"""

from __future__ import annotations

from pathlib import Path

DOCS = Path(__file__).resolve().parent
SECTIONS = DOCS / "sections"
MACHINE = "the project's 2-core AMD EPYC VM with 24 GiB of memory"

DOCUMENTS: dict[str, tuple[str, str, list[str]]] = {
    "PERFORMANCE.md": (
        "Performance",
        f"Measured figures only, each with its date, machine and the command that prints it. The "
        f"machine is {MACHINE}, shared with other jobs while these were taken (timings swing by up "
        "to 2×; ratios against peers are measured in the same run). Where a target is not reached, "
        "the section says so and by how much.",
        [
            "bench_bvh",
            "bench_dtw",
            "bench_pipeline",
            "e2e",
            "bench_scale",
            "bench_upload",
            "bench_live",
        ],
    ),
    "EVALUATION.md": (
        "Evaluation",
        "Accuracy of our implementation on UI-PRMD (public domain) beside the numbers the source "
        "papers publish. Each section gives the date, the machine (2-core AMD EPYC VM) and the "
        "command that regenerates it. Where a target is not reached, the section says so and by "
        "how much.",
        [
            "eval_periodic",
            "eval_landmarks",
            "eval_alignment",
            "eval_identification",
            "eval_assessment",
            "eval_mismatch",
            "eval_rigs_feedback",
            "eval_pipeline",
            "eval_mistakes",
            "clinical",
            "assessment_design",
            "eval_live",
        ],
    ),
    "RELIABILITY.md": (
        "Reliability and security",
        f"What protects a clinic's data and what we measured to show it, on {MACHINE}. Each "
        "section gives the date and the command that reproduces it; misses are stated with their "
        "size.",
        [
            "reliability_access",
            "reliability_fuzz",
            "reliability_faults",
            "reliability_load",
            "reliability_workers",
        ],
    ),
}


def assemble(title: str, intro: str, names: list[str]) -> str:
    parts = [f"# {title}\n\n{intro}\n"]
    for name in names:
        path = SECTIONS / f"{name}.md"
        if path.exists():
            parts.append(path.read_text(encoding="utf-8").strip() + "\n")
    return "\n".join(parts)


def main() -> None:
    for filename, (title, intro, names) in DOCUMENTS.items():
        (DOCS / filename).write_text(assemble(title, intro, names), encoding="utf-8")
        print(f"wrote docs/{filename}")


if __name__ == "__main__":
    main()
