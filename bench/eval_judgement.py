"""One judgement per repetition (issue 34): the rules of `analysis.pipeline.judgement`, checked
on the result JSON of every development UI-PRMD session and of mistakes made on purpose, and the
live words against the offline judgement of the same frames.

Offline: every session of ``data/ui-prmd/sessions`` (10 exercises × s01–s07, correct and
incorrect: 140) analysed cold (the model fitted from the exercise's tutor, s01's correct take,
alone), and each correct take with one mistake made on purpose (`bench.eval_mistakes.mistakes`:
reach cut to 55 %, the moving arm left down (arm exercises), the trunk leaned 20°, re-timed ×0.6
and ×1.6), as a first session. Each result's JSON (``analyse --json``) is checked
(`broken_rules`): never "overdone" and "incomplete" (nor "too fast" and "too slow") on one
repetition; no guidance against a correction naming its repetition; every failed repetition
with a reason; corrections whenever a repetition failed; no praise for a corrected part.

Live: sessions streamed frame by frame through `analysis.live.LiveAligner`; each live repetition's
words against the words of the offline judgement of the same frames (`offline_words`: the
offline code path's measurements of those frames — `prepare`, the repetition score, paper 001's
pace, the recording's clinical angles and compensations — judged by the same `judge`).

    .venv/bin/python -m bench.eval_judgement [--exercises m01,m07] [--jobs 1] [--live 20]
"""

from __future__ import annotations

import argparse
import os
import platform
import time
from collections import Counter
from collections.abc import Mapping, Sequence
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import Any

from analysis.assessment.findings import TRUNK
from analysis.bvh import Motion, map_joints, read
from analysis.clinical import angle_ranges, measure
from analysis.clinical.body import find_body
from analysis.clinical.labels import INSTRUCTIONS, split_side
from analysis.kinematics import kinematics, resample, scaled_positions
from analysis.live import LiveAligner, repetition_words
from analysis.pipeline import analyse
from analysis.pipeline.advice_stage import facts_of, judge_of, repetition_measures
from analysis.pipeline.clinical_stage import rounded
from analysis.pipeline.gestures import align_gesture, guidance, repetition_pace, usual_pace
from analysis.pipeline.judgement import AGAINST, judge
from analysis.pipeline.model import FittedModel
from analysis.pipeline.prepare import mirrored, prepare
from analysis.pipeline.repetition_stage import RULES, pace_reference
from analysis.pipeline.results import RepetitionResult
from analysis.pipeline.stages import scoring_features
from analysis.pipeline.tutor_parts import compensations
from bench.eval_assessment import load_sessions
from bench.eval_live import machine
from bench.eval_mistakes import cold_model, mistakes

DATA = Path("data/ui-prmd")
EXERCISES = [f"m{k:02d}" for k in range(1, 11)]
SUBJECTS = [f"s{k:02d}" for k in range(1, 8)]
TEMPO_KINDS = {"slow down": "fast", "speed up": "slow"}


def correction_kind(correction: Mapping[str, Any]) -> str:
    """The finding kind a correction of the result JSON says ("less", "more", "fast", …). The
    trunk's are read as a posture held ("Straighten your trunk"): the JSON does not tell them
    from its range, and the guidance's reach is of the joints the exercise trains, never the
    trunk in these exercises."""
    angle, direction = str(correction.get("angle", "")), str(correction.get("direction", ""))
    if not angle:
        return TEMPO_KINDS.get(direction, "")
    base = split_side(angle)[0]
    if base in TRUNK:  # "straighten" / "lean": a posture held (no reach), as a range would say
        return "held"
    kinds = [
        (k, text) for (b, k), (d, text) in INSTRUCTIONS.items() if b == base and d == direction
    ]
    if len(kinds) > 1:  # one direction for both ("turn"): the sentence tells which
        part, said = str(correction.get("part", "")), str(correction.get("text", ""))
        kinds = [(k, t) for k, t in kinds if said.startswith(t.format(part=part))] or kinds
    return kinds[0][0] if kinds else ""


def _repetition_rules(number: int, rep: Mapping[str, Any], corrections: Sequence[Any]) -> list[str]:
    """What one repetition breaks: two types of one axis, guidance against a correction naming
    it, a failure without a reason."""
    types = {g["type"] for g in rep.get("guidance", [])}
    out = [
        f"repetition {number}: {' and '.join(sorted(pair))}"
        for pair in ({"overdone", "incomplete"}, {"too fast", "too slow"}) if pair <= types
    ]  # fmt: skip
    for c in corrections:
        against = AGAINST.get(correction_kind(c), set()) & types
        if number in c.get("repetitions", []) and against:
            out.append(f"repetition {number}: {sorted(against)} beside {c['text']!r}")
    if rep.get("passed") is False and not rep.get("reasons"):
        out.append(f"repetition {number}: failed without a reason")
    return out


def broken_rules(result: Mapping[str, Any]) -> list[str]:
    """The rules of one judgement per repetition a result JSON breaks (module docstring)."""
    reps, advice = result.get("repetitions", []), result.get("advice", {})
    corrections = advice.get("corrections", [])
    out = [b for n, rep in enumerate(reps, 1) for b in _repetition_rules(n, rep, corrections)]
    if any(r.get("passed") is False for r in reps) and not corrections:
        out.append("failed repetitions and nothing to correct")
    out += [
        f"praised and corrected: {praise!r} beside {c['text']!r}"
        for praise in advice.get("went_well", []) for c in corrections
        if c.get("unit") == "°" and c.get("part") and c["part"] in praise
    ]  # fmt: skip
    return out


def judged(result: Mapping[str, Any]) -> Counter:
    """Counts for one result: analyses, with a broken rule, failed repetitions, without reason."""
    broken = broken_rules(result)
    failed = [r for r in result.get("repetitions", []) if r.get("passed") is False]
    return Counter({
        "results": 1, "broken": bool(broken), "failed": len(failed),
        "silent": sum(not r.get("reasons") for r in failed),
        "repetitions": len(result.get("repetitions", [])),
    })  # fmt: skip


def evaluate(data: Path, exercise: str) -> tuple[Counter, list[str]]:
    """Every session of one exercise and its correct takes' mistakes (a worker with --jobs)."""
    model = cold_model(data, exercise)
    tutor, sessions = load_sessions(data, exercise)
    counts, notes = Counter(), []
    for session in [tutor, *sessions]:
        cases = {"as recorded": session.motion}
        if session.correct:
            cases |= {kind: m for kind, (m, _) in mistakes(session.motion, exercise).items()}
        for kind, motion in cases.items():
            result = analyse(motion, model).to_json()
            counts += judged(result)
            notes += [f"{session.name} ({kind}): {b}" for b in broken_rules(result)]
    print(f"{exercise}: {counts['results']} results, {counts['broken']} break a rule", flush=True)
    return counts, notes


def offline_words(
    motion: Motion, model: FittedModel, live: Sequence[Mapping[str, Any]]
) -> list[str]:
    """The words of the offline judgement of each live repetition's frames (module docstring):
    the recording up to the repetition's end (the frames the live session had) prepared and
    measured as `analyse` does (`prepare`, `measure`, the compensations), the repetition scored
    (`stages.scoring_features`), paced (`gestures`) and judged (`judge`) by the offline
    pipeline's functions, on the side the live session counted it."""
    parts, papers = model.components, model.components.papers
    index, mirror, reference, tutor_frames = pace_reference(model)
    step, reps = parts.scoring_step, parts.tutor_reps
    prepared = prepare(motion, model.tutor.skeleton, model.fps, parts.axis.rep_frames)
    mapping = map_joints(model.joint_names, motion.skeleton.names)
    joints = [motion.skeleton.names.index(mapping[n]) for n in model.joint_names]
    words, paces = [], []
    for k, event in enumerate(live):
        a, b, side = int(event["start"]), int(event["end"]), bool(event["side"])
        # prepared as `prepare` does, without its length check (a first repetition's frames
        # may be shorter than a recording is allowed to be)
        at_rate = resample(motion.with_frames(motion.frames[: b + 1]), model.fps)
        kin, body = kinematics(at_rate), find_body(at_rate.skeleton)
        points = scaled_positions(at_rate, joints, kin)
        points = mirrored(points, parts.mirror) if side else points
        score = round(float(parts.scorer.score(scoring_features(points, a, b, parts))), 2)
        t0, t1 = reps[k % len(reps)]
        patient = prepared.local_q[a : b + 1 : step]
        aligned = align_gesture(papers.tutor_q[t0 : t1 + 1 : step], patient[:, index],
                                papers.joint_weights)  # fmt: skip
        tempo = (b - a + 1) / tutor_frames
        pace, reach = repetition_pace(patient[:, index], patient[:, mirror], reference, tempo)
        paces.append(pace)
        found = guidance(aligned, reach, pace, usual_pace(paces), RULES)
        rep = RepetitionResult(
            start=a, end=b, peak=a, score=score, reach=float(event["reach"]),
            tempo=round(tempo, 3), guidance=found,
            clinical_angles=rounded(angle_ranges(
                measure(at_rate, kin=kin, body=body).series, a, b)),
        )  # fmt: skip
        bent = compensations(kin.positions, body)
        measures = repetition_measures([rep], bent)[0]
        verdict = judge(facts_of(rep, measures, k + 1, None), judge_of(model, side))
        told = {"index": k, "passed": verdict.passed, "reasons": list(verdict.reasons)}
        words.append(repetition_words(told))
    return words


def streamed(motion: Motion, model: FittedModel) -> list[dict[str, Any]]:
    """The repetition events of a session streamed frame by frame through a live aligner, each
    with the side it was counted on (``side``: 1 for the mirror image)."""
    aligner = LiveAligner(model, motion.skeleton, motion.fps)
    out = []
    for values in motion.frames:
        out += [{**e, "side": aligner._side} for e in aligner.push(values)]
    out += [{**e, "side": aligner._side} for e in aligner.finish()]
    return [e for e in out if e["event"] == "repetition"]


def live_against_offline(data: Path, name: str) -> tuple[Counter, list[str]]:
    """One streamed session: its live repetitions, and those whose words differ from the
    offline judgement of the same frames."""
    exercise = Path(name).name[:3]
    model = cold_model(data, exercise)
    motion = read(data / name)
    live = streamed(motion, model)
    offline = offline_words(motion, model, live)
    differ = [f"{name} {e['words']!r} / offline {o!r}" for e, o in zip(live, offline, strict=True)
              if e["words"] != o]  # fmt: skip
    failed = [e for e in live if not e["passed"]]
    counts = Counter({"sessions": 1, "repetitions": len(live), "differ": len(differ),
                      "failed": len(failed), "silent": sum(not e["reasons"] for e in failed),
                      "tutor": sum("tutor" in e["words"].lower() for e in live)})  # fmt: skip
    print(f"live {name}: {len(live)} repetitions, {len(differ)} differ", flush=True)
    return counts, differ


def live_sessions(count: int) -> list[str]:
    """``count`` development sessions (a fixed choice): every exercise in turn, the incorrect
    takes first, subjects s02–s07 in turn."""
    return [
        f"sessions/{EXERCISES[k % 10]}_{SUBJECTS[1 + k % 6]}_"
        f"{'incorrect' if k < 10 else 'correct'}.bvh.gz"
        for k in range(count)
    ]


def _table(rows: Mapping[str, Counter]) -> list[str]:
    lines = ["| exercise | results | with a broken rule | repetitions | failed | failed without "
             "a reason |", "|---|---|---|---|---|---|"]  # fmt: skip
    total: Counter = Counter()
    for name, c in rows.items():
        total += c
        lines.append(f"| {name} | {c['results']} | {c['broken']} | {c['repetitions']} | "
                     f"{c['failed']} | {c['silent']} |")  # fmt: skip
    lines.append(f"| **all** | {total['results']} | **{total['broken']}** | "
                 f"{total['repetitions']} | {total['failed']} | "
                 f"**{total['silent']}** |")  # fmt: skip
    return lines


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--data", type=Path, default=DATA)
    parser.add_argument("--exercises", default=",".join(EXERCISES))
    parser.add_argument("--jobs", type=int, default=1)
    parser.add_argument("--live", type=int, default=20, help="sessions streamed live")
    parser.add_argument("--live-only", action="store_true", help="skip the offline results")
    args = parser.parse_args(argv)
    started = time.perf_counter()
    exercises = args.exercises.split(",")
    names = [n for n in live_sessions(args.live) if Path(n).name[:3] in exercises]
    with ProcessPoolExecutor(max_workers=max(1, args.jobs)) as pool:
        todo = [] if args.live_only else exercises
        offline = list(pool.map(evaluate, [args.data] * len(todo), todo))
        live = list(pool.map(live_against_offline, [args.data] * len(names), names))
    rows = {e: c for e, (c, _) in zip(todo, offline, strict=True)}
    told = sum((c for c, _ in live), Counter())
    print("\n".join(["", *_table(rows), ""]))
    print(
        f"Live: {told['sessions']} sessions streamed, {told['repetitions']} repetitions, "
        f"{told['differ']} whose words differ from the offline judgement of the same frames; "
        f"{told['failed']} failed, {told['silent']} of them without a reason; "
        f"{told['tutor']} naming the tutor."
    )
    for note in [n for _, ns in offline for n in ns] + [d for _, ds in live for d in ds]:
        print("  -", note)
    print(
        f"\n{time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}, {machine()}, Python "
        f"{platform.python_version()}, load {os.getloadavg()[0]:.1f}, --jobs {args.jobs}, "
        f"{time.perf_counter() - started:.0f} s"
    )


if __name__ == "__main__":
    main()
