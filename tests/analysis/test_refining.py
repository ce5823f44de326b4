"""Landmark refining (thesis 004, 5.5, eqs 5.27–5.33) and our grammar and relocation steps."""

import numpy as np
import pytest

from analysis.landmarks.key_poses import KeyPoses
from analysis.landmarks.refining import (
    RefineOptions,
    cluster,
    em_clusters,
    gap_clusters,
    mean_poses,
    refine,
    select,
    temporal_clusters,
)
from analysis.landmarks.regularise import (
    GrammarOptions,
    farthest_frame,
    farthest_types,
    regularise,
    relocate,
    tempo_costs,
    transitions,
    typical_gaps,
)


def cands(frames, types):
    return KeyPoses(np.asarray(frames, dtype=np.int64), np.asarray(types, dtype=np.int64))


def test_temporal_clusters_eq_5_29_by_hand():
    # gaps 1, 1, 18, 1, 29: ratios (from the third landmark) 1, 18, 1/18, 29 against β = 2
    assert temporal_clusters([10, 11, 12, 30, 31, 60], 2.0).tolist() == [1, 1, 1, 2, 2, 3]


def test_temporal_clusters_keep_the_first_two_together_and_need_a_ratio():
    # χ_1 and χ_2 always share a cluster; evenly spaced landmarks never start a new one.
    assert temporal_clusters([0, 50], 2.0).tolist() == [1, 1]
    assert temporal_clusters([0, 30, 60, 90], 2.0).tolist() == [1, 1, 1, 1]


def test_gap_clusters_split_at_gaps_larger_than_beta():
    assert gap_clusters([10, 11, 12, 30, 31, 60], 5.0).tolist() == [1, 1, 1, 2, 2, 3]
    assert gap_clusters([0, 5], 5.0).tolist() == [1, 1]


def test_mean_poses_eq_5_30():
    sig = np.array([[0.0, 1.0], [1.0, 1.0], [2.0, 3.0], [3.0, 5.0]])
    means = mean_poses(sig, [0, 2, 3], [1, 1, 2])
    assert set(means) == {1, 2}
    np.testing.assert_allclose(means[1], [1.0, 2.0])
    np.testing.assert_allclose(means[2], [3.0, 5.0])


MEANS = {1: np.array([1.0]), 2: np.array([2.0])}


def test_mu1_takes_the_member_closest_to_its_own_types_tutor_mean():
    sig = np.array([[1.0], [3.0], [0.0]])
    c = cands([0, 1, 2], [1, 2, 2])
    out = select(c, np.zeros(3, dtype=np.int64), sig, MEANS, "mu1")  # eq 5.31
    assert (out.frames.tolist(), out.types.tolist()) == ([0], [1])


def test_mu2_takes_the_majority_type_first():
    sig = np.array([[1.0], [3.0], [0.0]])
    c = cands([0, 1, 2], [1, 2, 2])
    out = select(c, np.zeros(3, dtype=np.int64), sig, MEANS, "mu2")  # eqs 5.32–5.33
    assert (out.frames.tolist(), out.types.tolist()) == ([1], [2])


def test_selection_is_per_cluster_and_sorted_by_frame():
    sig = np.array([[2.1], [1.9], [5.0], [1.0], [0.7]])
    c = cands([0, 1, 2, 3, 4], [2, 2, 2, 1, 1])
    out = select(c, np.array([1, 1, 1, 0, 0]), sig, MEANS, "mu1")
    assert (out.frames.tolist(), out.types.tolist()) == ([0, 3], [2, 1])


def test_extreme_selection_goes_farthest_along_the_type_axis():
    sig = np.array([[1.8], [2.6], [2.1]])  # the tutor's end of range is 2, this patient goes 2.6
    out = select(cands([0, 1, 2], [2, 2, 2]), np.zeros(3, dtype=np.int64), sig, MEANS, "extreme")
    assert out.frames.tolist() == [1]


def _bursts():
    frames = np.r_[10:20, 60:70]
    sig = np.zeros((80, 1))
    sig[frames, 0] = np.r_[np.linspace(0.5, 1.4, 10), np.linspace(1.5, 2.4, 10)]
    sig[[14, 64], 0] = [1.0, 2.0]  # the members closest to the tutor's means
    return cands(frames, [1] * 10 + [2] * 10), sig


def test_em_and_kmeans_find_the_two_bursts():
    c, sig = _bursts()
    for method in ("em", "kmeans", "gap"):
        labels = cluster(c, sig, RefineOptions(clustering=method, n_clusters=2))
        assert len(set(labels[:10].tolist())) == 1, method
        assert len(set(labels[10:].tolist())) == 1, method
        assert labels[0] != labels[10], method


def test_refine_keeps_one_landmark_per_burst():
    c, sig = _bursts()
    out = refine(c, sig, MEANS, RefineOptions(clustering="em", selection="mu1", n_clusters=2))
    assert (out.frames.tolist(), out.types.tolist()) == ([14, 64], [1, 2])


def test_em_chooses_the_number_of_clusters_by_bic():
    rng = np.random.default_rng(0)
    points = np.vstack(
        [rng.normal(0, 1, (40, 2)), rng.normal(20, 1, (40, 2)), rng.normal(40, 1, (40, 2))]
    )
    labels = em_clusters(points, [1, 2, 3, 4, 5], seed=0)
    assert len(set(labels.tolist())) == 3
    assert len(set(labels[:40].tolist())) == 1


def test_kmeans_without_a_count_uses_the_gap_estimate():
    c, sig = _bursts()
    labels = cluster(c, sig, RefineOptions(clustering="kmeans"))
    assert len(set(labels.tolist())) == 2


def test_a_single_candidate_is_its_own_cluster():
    for method in ("em", "kmeans", "tc", "gap"):
        out = refine(cands([7], [2]), np.zeros((10, 1)), MEANS, RefineOptions(clustering=method))
        assert (out.frames.tolist(), out.types.tolist()) == ([7], [2]), method


def test_refine_of_nothing_is_nothing():
    out = refine(cands([], []), np.zeros((5, 1)), MEANS)
    assert out.frames.size == 0


def test_transitions_from_training_sequences():
    allowed = transitions([[1, 2, 1, 2, 1], [1, 3, 1]], 3)
    pairs = {(int(a), int(b)) for a, b in np.argwhere(allowed)}
    assert pairs == {(1, 2), (2, 1), (1, 3), (3, 1)}


POSES = np.array([0.0, 1.0, 5.0, 3.0, 0.0, 2.0, 0.0])[:, None, None]  # (F, J=1, 1)


def test_farthest_frame_between_two_landmarks():
    assert farthest_frame(POSES, 0, 4) == 2
    assert farthest_frame(POSES, 4, 6) == 5


def test_farthest_types_are_learnt_from_training_samples():
    # type 2 at frame 2 is the farthest pose from frame 0 before frame 4; type 3 at frame 4 is
    # not the farthest from frame 2 before frame 6 (frame 3 would be... no: 4 is 5 away, 3 is 2)
    # so make it a mid-way pose: type 3 at frame 3 between 2 and 6 (farthest is 4).
    samples = [(POSES, np.array([0, 2, 3, 6]), np.array([1, 2, 3, 1]))]
    assert farthest_types(samples, tolerance=0) == {2}
    assert farthest_types(samples, tolerance=1) == {2, 3}


def test_relocate_moves_only_the_given_types():
    out = relocate(cands([0, 1, 4], [1, 2, 1]), POSES, {2})
    assert out.frames.tolist() == [0, 2, 4]


GRAMMAR = transitions([[1, 2, 1]], 2)
FAR = {1: np.array([0.0]), 2: np.array([3.0])}


def _ramp_signature():
    sig = np.zeros((11, 1))
    sig[3:8, 0] = [1.0, 2.0, 3.0, 2.0, 1.0]
    return sig


def test_grammar_retypes_an_end_of_range_seen_as_a_start():
    out = regularise(cands([0, 5, 10], [1, 1, 1]), _ramp_signature(), FAR, GRAMMAR)
    assert (out.frames.tolist(), out.types.tolist()) == ([0, 5, 10], [1, 2, 1])


def test_grammar_puts_back_a_missed_end_of_range():
    out = regularise(cands([0, 10], [1, 1]), _ramp_signature(), FAR, GRAMMAR)
    assert (out.frames.tolist(), out.types.tolist()) == ([0, 5, 10], [1, 2, 1])


def test_grammar_drops_a_duplicate_start_during_a_pause():
    sig = np.zeros((11, 1))
    sig[10] = 3.0
    out = regularise(cands([0, 3, 10], [1, 1, 2]), sig, FAR, GRAMMAR, GrammarOptions())
    assert (out.types.tolist(), out.frames.tolist()[-1]) == ([1, 2], 10)
    assert out.frames.size == 2


def test_grammar_keeps_a_valid_sequence_unchanged():
    c = cands([0, 5, 10], [1, 2, 1])
    out = regularise(c, _ramp_signature(), FAR, GRAMMAR)
    assert (out.frames.tolist(), out.types.tolist()) == ([0, 5, 10], [1, 2, 1])


def test_typical_gaps_are_medians_per_type_pair():
    gaps = typical_gaps([([0, 10, 30, 40], [1, 2, 1, 2]), ([0, 14, 20], [1, 2, 1])], 2)
    assert gaps[1, 2] == 10.0 and gaps[2, 1] == 13.0  # medians of (10, 10, 14) and (20, 6)
    assert gaps[1, 1] == 0.0 and gaps.shape == (3, 3)


def test_tempo_cost_grows_as_a_gap_falls_below_its_share_of_the_typical_one():
    gaps = np.array([[0.0, 0.0], [0.0, 20.0]])
    options = GrammarOptions(tempo=4.0, short=0.5)  # costly below 10 frames
    assert tempo_costs(12.0, gaps, options)[1, 1] == 0.0
    assert tempo_costs(5.0, gaps, options)[1, 1] == pytest.approx(2.0)
    assert tempo_costs(0.0, gaps, options)[1, 1] == pytest.approx(4.0)
    assert np.all(tempo_costs(0.0, gaps, options)[0] == 0.0)  # never seen: no prior


def test_tempo_prior_drops_a_repetition_far_quicker_than_training():
    frames, types = [0, 20, 40, 43, 46, 66, 86], [1, 2, 1, 2, 1, 2, 1]
    sig = np.zeros((87, 1))
    sig[[20, 43, 66], 0] = 3.0  # every landmark sits exactly at its type's pose
    gaps = typical_gaps([(frames[:3], types[:3])], 2)  # 20 frames each way
    plain = regularise(cands(frames, types), sig, FAR, GRAMMAR, GrammarOptions(), gaps=gaps)
    assert plain.frames.tolist() == frames  # tempo 0: a valid sequence stays as it is
    out = regularise(cands(frames, types), sig, FAR, GRAMMAR, GrammarOptions(tempo=4.0), gaps=gaps)
    assert out.types.tolist() == [1, 2, 1, 2, 1] and 43 not in out.frames.tolist()


def _reference_bridges(distances, span, allowed, insert):
    """The bridges of one pair of kept landmarks, as numpy arrays (the programme's reference)."""
    from analysis.landmarks.regularise import pose_costs

    width = allowed.shape[0]
    via = np.full((width, width), np.inf)
    kind = np.full((width, width), -1, dtype=np.int64)
    where = np.full((width, width), -1, dtype=np.int64)
    inside = distances[span[0] + 1 : span[1]]
    if inside.shape[0]:
        at = np.argmin(inside, axis=0)
        price = insert + pose_costs(inside)[at, np.arange(width)]
        for sigma in range(width):
            c = np.where(allowed[:, sigma][:, None] & allowed[sigma][None, :], price[sigma], np.inf)
            better = c < via
            via[better], kind[better], where[better] = c[better], sigma, span[0] + 1 + at[sigma]
    return via, kind, where


def _reference_regularise(landmarks, signature, means, allowed, options, *, gaps):
    """`regularise`'s programme written with numpy arrays, one (width, width) step at a time
    (the compiled one must give the same costs and back-pointers, bit for bit)."""
    from analysis.landmarks.regularise import pose_costs, pose_distances

    n, width = landmarks.frames.size, allowed.shape[0]
    distances = pose_distances(signature, means, width)
    retyped = np.arange(width)[None, :] != landmarks.types[:, None]
    cost = pose_costs(distances[landmarks.frames]) + options.retype * retyped
    best = cost + options.delete * np.arange(n)[:, None]
    back = np.full((n, width, 4), -1, dtype=np.int64)
    for k in range(1, n):
        for j in range(max(0, k - options.lookback - 1), k):
            span = (int(landmarks.frames[j]), int(landmarks.frames[k]))
            via, kind, where = _reference_bridges(distances, span, allowed, options.insert)
            direct = np.where(allowed, 0.0, np.inf)
            if options.tempo > 0:
                direct = direct + tempo_costs(float(span[1] - span[0]), gaps, options)
                half = tempo_costs((span[1] - span[0]) / 2.0, gaps, options)
                sigma = np.maximum(kind, 0)
                before, after = np.indices(kind.shape)
                via = via + np.where(kind >= 0, half[before, sigma] + half[sigma, after], 0.0)
            total = best[j][:, None] + np.minimum(direct, via) + options.delete * (k - j - 1)
            src, cols = np.argmin(total, axis=0), np.arange(width)
            value = total[src, cols] + cost[k]
            better = value < best[k]
            bridged = via[src, cols] < direct[src, cols]
            record = np.column_stack([
                np.full(width, j), src, np.where(bridged, kind[src, cols], -1),
                np.where(bridged, where[src, cols], -1),
            ])  # fmt: skip
            best[k, better], back[k, better] = value[better], record[better]
    return best, back


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("tempo", [0.0, 3.0])
def test_compiled_grammar_typing_matches_the_array_formulas_bit_for_bit(seed, tempo, monkeypatch):
    import analysis.landmarks.regularise as module

    rng = np.random.default_rng(seed)
    n_types = int(rng.integers(2, 5))
    frames = np.sort(rng.choice(np.arange(200), size=int(rng.integers(2, 30)), replace=False))
    types = rng.integers(1, n_types + 1, frames.size)
    sig = rng.normal(size=(200, 3))
    means = {t: rng.normal(size=3) for t in range(1, n_types + 1) if t != 2 or seed % 2}
    allowed = rng.random((n_types + 1, n_types + 1)) < 0.6
    gaps = typical_gaps([(frames, types)], n_types)
    options = GrammarOptions(tempo=tempo, lookback=int(rng.integers(1, 5)))
    landmarks = cands(frames, types)
    seen = {}

    def kept(marks, total, back):
        seen["total"], seen["back"] = total, back
        return marks

    monkeypatch.setattr(module, "_regularised", kept)
    module.regularise(landmarks, sig, means, allowed, options, gaps=gaps)
    best, back = _reference_regularise(landmarks, sig, means, allowed, options, gaps=gaps)
    n = frames.size
    expected = best + options.delete * (n - 1 - np.arange(n))[:, None]
    assert seen["total"].tobytes() == expected.tobytes()
    assert np.array_equal(seen["back"], back)
