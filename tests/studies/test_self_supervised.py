"""Learning gestures from effects: the world, the labels and the learners
(glu.studies.learning.self_supervised, online, learned_recognizers).

References: the network's own single queries, the gesture generator's own draws, the unweighted recogniser
training, a hand-written online loop over the readable E- and M-steps, learners run alone against learners
run together, learners that must coincide (clusters named by certain labels and by the truth), counting.
"""

from __future__ import annotations

import numpy as np
import pytest

from glu.bn import learn_bn, make_engine
from glu.data import load_experiments
from glu.errors import DataError
from glu.gestures.recognizer import train_recognizer
from glu.hmm import GMMHMMParams, TrainingConfig, expected_stats, maximise, train
from glu.studies.learning import learned_recognizers as lr_
from glu.studies.learning import online as ol
from glu.studies.learning import self_supervised as ss

SMALL = TrainingConfig(n_states=3, n_mix=1, n_iter=20, tol=1e-3)


@pytest.fixture(scope="module")
def engine():
    return make_engine(learn_bn(load_experiments("synthetic")))


# ------------------------------------------------------------------ the world


def test_episodes_share_actions_and_gestures_across_ambiguities(engine):
    a = ss.simulate_episodes(engine, ss.AMBIGUITIES["mixed"], 12, seed=3)
    b = ss.simulate_episodes(engine, ss.AMBIGUITIES["still"], 12, seed=3)
    assert np.array_equal(a.actions, b.actions)
    assert all(np.array_equal(x, y) for x, y in zip(a.features, b.features, strict=True))
    held = ss.simulate_episodes(engine, ss.AMBIGUITIES["mixed"], 12, seed=3, offset=ss.TEST_OFFSET)
    assert not any(np.array_equal(x, y) for x, y in zip(a.features, held.features, strict=True))
    other = ss.simulate_episodes(engine, ss.AMBIGUITIES["mixed"], 12, seed=4)
    assert not np.array_equal(a.actions, other.actions) or not np.array_equal(
        a.features[0], other.features[0]
    )


def test_objects_that_never_move_and_failed_taps(engine):
    schema = engine.bn.schema
    slow, tap = schema.values_of("ObjVel").index("slow"), schema.values_of("Action").index("tap")
    actions = np.arange(600) % 3
    world, seen = ss.draw_world(engine, actions, ss.AMBIGUITIES["still"], seed=0)
    assert np.all(world["ObjVel"] == slow) and np.array_equal(seen["ObjVel"], world["ObjVel"])
    failing = ss.Ambiguity("all fail", failed_taps=1.0)
    world, _ = ss.draw_world(engine, actions, failing, seed=0)
    assert np.all(world["ObjVel"][actions == tap] == slow)
    normal, _ = ss.draw_world(engine, actions, ss.AMBIGUITIES["mixed"], seed=0)
    assert np.mean(normal["ObjVel"][actions == tap] == slow) < 0.5  # taps usually move things
    # the other actions' effects keep the network's distribution: p(slow | grasp) as the engine says
    p = engine.query(["ObjVel"], {"Action": "grasp"})["ObjVel"][slow]
    grasp = world["ObjVel"][actions == 0]
    assert abs(np.mean(grasp == slow) - p) < 4 * np.sqrt(p * (1 - p) / len(grasp))


def test_perception_noise_replaces_the_effect_by_a_uniform_value(engine):
    actions = np.arange(3000) % 3
    world, seen = ss.draw_world(engine, actions, ss.Ambiguity("blind", perception_noise=1.0), seed=1)
    freq = np.bincount(seen["ObjVel"], minlength=3) / len(actions)
    np.testing.assert_allclose(freq, 1 / 3, atol=0.03)
    assert np.array_equal(seen["Shape"], world["Shape"])  # the object is seen as it is
    world, seen = ss.draw_world(engine, actions, ss.Ambiguity("some", perception_noise=0.3), seed=1)
    changed = np.mean(seen["ObjVel"] != world["ObjVel"])
    assert abs(changed - 0.3 * 2 / 3) < 0.03  # a uniform redraw keeps the value one time in three


def test_the_easy_world_is_the_generator_as_it_was(engine):
    """The easy world draws exactly the generator's default gestures, from each episode's own generator."""
    from glu.gestures.synthetic import synthesize_gesture

    ep = ss.simulate_episodes(engine, ss.AMBIGUITIES["mixed"], 5, seed=7, world=ss.WORLDS["easy"])
    names = engine.bn.schema.values_of("Action")
    for i, (a, x) in enumerate(zip(ep.actions, ep.features, strict=True)):
        rng = np.random.default_rng(np.random.SeedSequence(7, spawn_key=(ss.GESTURE_KEY, i)))
        np.testing.assert_array_equal(x, synthesize_gesture(names[a], rng, noise=0.02).features())


def test_the_hard_world_turns_varies_and_frames_each_person(engine):
    from glu.gestures.synthetic import View, synthesize_gesture

    hard = ss.WORLDS["hard"]
    views = hard.views(200, seed=3)
    yaws = np.array([v.yaw_deg for v in views])
    assert set(yaws) <= set(np.arange(-60, 61, 5.0)) and len(set(yaws)) > 10
    assert all(v.variety == hard.variety and v.body_frame for v in views)
    assert [v.yaw_deg for v in hard.views(200, seed=3)] == list(yaws)  # seeded
    ep = ss.simulate_episodes(engine, ss.AMBIGUITIES["mixed"], 6, seed=3, world=hard)
    names = engine.bn.schema.values_of("Action")
    for i, (a, x) in enumerate(zip(ep.actions, ep.features, strict=True)):
        rng = np.random.default_rng(np.random.SeedSequence(3, spawn_key=(ss.GESTURE_KEY, i)))
        view = View(yaw_deg=yaws[i], variety=hard.variety, body_frame=True)
        np.testing.assert_allclose(
            x, synthesize_gesture(names[a], rng, noise=hard.noise, view=view).features()
        )


def test_in_the_hard_world_the_slowest_taps_fail(engine):
    """Effects follow the gesture: the failing taps are those whose gesture is slowest (the generator's own
    duration and amplitude), not random ones; in the easy world failures ignore the gesture."""
    from glu.studies.episodes import gesture_speed

    schema = engine.bn.schema
    slow, tap = schema.values_of("ObjVel").index("slow"), schema.values_of("Action").index("tap")
    actions = np.arange(900) % 3
    q = gesture_speed(
        [np.random.default_rng(np.random.SeedSequence(2, spawn_key=(ss.GESTURE_KEY, i))) for i in range(900)]
    ).quantile
    taps = actions == tap
    world, _ = ss.draw_world(engine, actions, ss.AMBIGUITIES["failed_taps"], 2, world=ss.WORLDS["hard"])
    assert np.all(world["ObjVel"][taps & (q < 0.5)] == slow)
    fast = taps & (q >= 0.5)
    assert np.mean(world["ObjVel"][fast] == slow) < 0.5
    world, _ = ss.draw_world(engine, actions, ss.AMBIGUITIES["failed_taps"], 2, world=ss.WORLDS["easy"])
    stays = world["ObjVel"] == slow
    assert abs(stays[taps & (q < 0.5)].mean() - stays[fast].mean()) < 0.15  # speed makes no difference
    # still objects never move, whatever the gesture
    world, _ = ss.draw_world(engine, actions, ss.AMBIGUITIES["still"], 2, world=ss.WORLDS["hard"])
    assert np.all(world["ObjVel"] == slow)


def test_random_labels_are_right_as_often_and_wrong_uniformly():
    """Binomial bounds: right with the given probability, each wrong action equally likely."""
    n, k, acc = 30000, 3, 0.55
    true = np.arange(n) % k
    lab = ss.matched_random_labels(true, acc, k, np.random.default_rng(0)).argmax(axis=1)
    right = lab == true
    assert abs(right.mean() - acc) < 4 * np.sqrt(acc * (1 - acc) / n)
    wrong = (lab[~right] - true[~right]) % k  # 1 or 2: which other action
    assert abs(np.mean(wrong == 1) - 0.5) < 4 * np.sqrt(0.25 / (~right).sum())
    with pytest.raises(DataError, match="probability"):
        ss.matched_random_labels(true, 1.5, k, np.random.default_rng(0))


def test_first_labels_by_counting():
    true = np.array([2, 0, 2, 2, 1, 0, 0, 2])
    w = ss.first_labels(true, 2, 3)
    for i in range(len(true)):
        earlier = int(np.sum(true[:i] == true[i]))
        assert w[i].tolist() == (ss.one_hot(true[i : i + 1], 3)[0] * (earlier < 2)).tolist()


def test_bad_ambiguities_are_refused():
    with pytest.raises(DataError, match="probability"):
        ss.Ambiguity("x", failed_taps=1.5)


def test_network_posteriors_equal_single_queries(engine):
    ep = ss.simulate_episodes(engine, ss.AMBIGUITIES["mixed"], 8, seed=2)
    schema = engine.bn.schema
    for words in (False, True):
        p = ss.network_posteriors(engine, ep.perceived, ep.world, words)
        for i in range(8):
            ev = {n: schema.values_of(n)[v[i]] for n, v in ep.perceived.items()}
            if words:
                ev |= {w: schema.values_of(w)[ep.world[w][i]] for w in schema.word_nodes}
            np.testing.assert_allclose(p[i], engine.query(["Action"], ev)["Action"], rtol=1e-12)


def test_impossible_evidence_falls_back_on_the_object(engine):
    """An episode whose words contradict its object (the word "box" heard of a sphere) is labelled by the
    object alone; the others as before; words=True without the world's words is refused."""
    ep = ss.simulate_episodes(engine, ss.AMBIGUITIES["mixed"], 8, seed=2)
    schema = engine.bn.schema
    world = {k: v.copy() for k, v in ep.world.items()}
    spheres = np.flatnonzero(ep.perceived["Shape"] == schema.values_of("Shape").index("sphere"))
    i = int(spheres[0])
    world["box"][i] = schema.values_of("box").index("present")
    p = ss.network_posteriors(engine, ep.perceived, world, words=True)
    obj = {n: schema.values_of(n)[ep.perceived[n][i]] for n in ("Color", "Shape", "Size")}
    np.testing.assert_allclose(p[i], engine.query(["Action"], obj)["Action"], rtol=1e-12)
    others = np.delete(np.arange(8), i)
    np.testing.assert_allclose(p[others], ss.network_posteriors(engine, ep.perceived, ep.world, True)[others])
    with pytest.raises(DataError, match="words=True needs the episodes' world"):
        ss.network_posteriors(engine, ep.perceived, words=True)


def test_bad_worlds_and_readings_are_refused():
    with pytest.raises(DataError, match="world 'w': noise=1.5 must be metres in \\[0, 1\\)"):
        ss.World("w", noise=1.5)
    with pytest.raises(DataError, match="world 'w': max_yaw=200 must be degrees in \\[0, 180\\]"):
        ss.World("w", max_yaw=200)
    with pytest.raises(DataError, match="unknown posterior reading 'vote'; allowed: "):
        ss.p_hmm_reading(np.zeros((1, 3)), np.ones(1), "vote")
    with pytest.raises(DataError, match="the 'true' baseline needs the true actions"):
        ss.label_weights("true", np.full((1, 3), 1 / 3))


# ------------------------------------------------------------------ labels


def test_labelling_schemes():
    p = np.array([[0.5, 0.3, 0.2], [0.05, 0.92, 0.03]])
    np.testing.assert_array_equal(ss.label_weights("hard", p), [[1, 0, 0], [0, 1, 0]])
    np.testing.assert_array_equal(ss.label_weights("soft", p), p)
    np.testing.assert_array_equal(ss.label_weights("confident", p, 0.9), [[0, 0, 0], [0, 1, 0]])
    q = np.array([[0.2, 0.2, 0.6], [0.1, 0.1, 0.8]])
    fused = ss.label_weights("iterative", p, p_hmm=q)
    np.testing.assert_allclose(fused[0], np.array([0.1, 0.06, 0.12]) / 0.28)
    np.testing.assert_array_equal(ss.label_weights("iterative", p), p)  # no HMMs yet: the network alone
    np.testing.assert_array_equal(ss.label_weights("true", p, true=np.array([2, 0])), [[0, 0, 1], [1, 0, 0]])
    with pytest.raises(DataError, match="unknown labelling scheme"):
        ss.label_weights("guess", p)


def test_per_frame_reading_tempers_the_likelihoods():
    ll = np.array([[-100.0, -110.0, -np.inf]])
    sharp = ss.p_hmm_reading(ll, np.array([50]), "likelihood")
    soft = ss.p_hmm_reading(ll, np.array([50]), "per-frame")
    np.testing.assert_allclose(sharp[0, :2], [1 / (1 + np.exp(-10)), np.exp(-10) / (1 + np.exp(-10))])
    np.testing.assert_allclose(soft[0, :2], [1 / (1 + np.exp(-0.2)), np.exp(-0.2) / (1 + np.exp(-0.2))])
    assert sharp[0, 2] == soft[0, 2] == 0


def test_best_matching_finds_the_permutation():
    counts = np.array([[1, 9, 0], [0, 1, 8], [7, 0, 2]], dtype=float)
    np.testing.assert_array_equal(ss.best_matching(counts), [1, 2, 0])


# ------------------------------------------------------------------ batch learning


def _corpus(engine, n=36, seed=0):
    ep = ss.simulate_episodes(engine, ss.AMBIGUITIES["mixed"], n, seed)
    return ep, engine.bn.schema.values_of("Action")


def test_true_labels_train_what_the_recogniser_trains(engine):
    ep, actions = _corpus(engine)
    learned = lr_.learn_recognizer(
        ep.features, "true", true=ep.actions, actions=actions, config=SMALL, seed=1
    )
    by_action = {
        a: [x for x, t in zip(ep.features, ep.actions, strict=True) if t == k] for k, a in enumerate(actions)
    }
    plain = train_recognizer(by_action, SMALL, seed=1, warn=False)
    for a in actions:
        np.testing.assert_allclose(
            learned.recognizer.models[a].means, plain.models[a].means, rtol=1e-7, atol=1e-9
        )
    # soft labels that are certain are the true labels
    certain = lr_.learn_recognizer(
        ep.features, "soft", ss.one_hot(ep.actions, 3), actions=actions, config=SMALL, seed=1
    )
    for a in actions:
        np.testing.assert_allclose(
            certain.recognizer.models[a].means, plain.models[a].means, rtol=1e-7, atol=1e-9
        )


def test_iterative_and_unsupervised_relabel_until_the_labels_settle(engine):
    ep, actions = _corpus(engine, 30, seed=5)
    p = ss.network_posteriors(engine, ep.perceived, ep.world, words=True)
    it = lr_.learn_recognizer(ep.features, "iterative", p, true=ep.actions, actions=actions, config=SMALL)
    assert 2 <= it.rounds <= 10
    np.testing.assert_allclose(it.weights.sum(axis=1), 1.0)
    un = lr_.learn_recognizer(ep.features, "unsupervised", true=ep.actions, actions=actions, config=SMALL)
    assert set(un.recognizer.actions) <= set(actions)
    with pytest.raises(DataError, match="needs p_bn"):
        lr_.learn_recognizer(ep.features, "soft", actions=actions, config=SMALL)


@pytest.mark.slow
def test_batch_learning_reports_each_model_and_refuses_bad_schemes(engine):
    ep, actions = _corpus(engine, 12)
    calls = []
    lr_.learn_recognizer(
        ep.features, "true", true=ep.actions, actions=actions, config=SMALL, progress=calls.append
    )
    assert calls == list(actions)  # true labels: one round, one model per action
    with pytest.raises(DataError, match="unknown labelling scheme 'guess'; allowed: "):
        lr_.learn_recognizer(ep.features, "guess")
    with pytest.raises(DataError, match="the unsupervised baseline needs the true actions"):
        lr_.learn_recognizer(ep.features, "unsupervised", actions=actions, config=SMALL)
    with pytest.raises(DataError, match="unknown ambiguity 'foggy'; allowed: "):
        lr_.learn_gestures(engine, 12, "hard", ambiguity="foggy")


def test_an_action_no_episode_is_labelled_with_is_one_error(engine):
    """Hard labels of 10 episodes (seed 1) that never name tap: no tap model, which the error says."""
    ep = ss.simulate_episodes(engine, ss.AMBIGUITIES["mixed"], 10, 1)
    tap = engine.bn.schema.values_of("Action").index("tap")
    assert (ss.network_posteriors(engine, ep.perceived, ep.world).argmax(axis=1) != tap).all()
    with pytest.raises(DataError, match="no episode was labelled tap \\(hard labels, mixed\\); watch more"):
        lr_.learn_gestures(engine, 10, "hard", seed=1, config=SMALL)


# ------------------------------------------------------------------ online learning


def _stream(engine, n=40, seed=0, test=12):
    ep = ss.simulate_episodes(engine, ss.AMBIGUITIES["mixed"], n, seed)
    held = ss.simulate_episodes(
        engine, ss.AMBIGUITIES["mixed"], test, seed, offset=ss.TEST_OFFSET, balanced=True
    )
    p = ss.network_posteriors(engine, ep.perceived, ep.world, words=True)
    return ep, held, p


def test_the_online_update_is_stepwise_em_over_the_readable_steps(engine):
    """One true-label learner, replayed by hand with glu.hmm.em's reference E- and M-steps."""
    ep, held, _ = _stream(engine, 30)
    settings = ol.OnlineSettings(config=SMALL, init_weight=3.0, init_iter=5, step=0.8)
    actions = engine.bn.schema.values_of("Action")
    run = ol.learn_online(ep.features, ep.actions, "true", None, actions, settings, seed=2)
    cfg = SMALL.replace(n_iter=5)
    models, mean, total, buf = {}, {}, {}, {a: [] for a in range(3)}
    for X, a in zip(ep.features, ep.actions.tolist(), strict=True):
        if a in models:
            unit = expected_stats([X], models[a])
            total[a] += 1.0
            eta = min(1.0, 1.0 / total[a] ** 0.8)
            mean[a] = mean[a].scaled(1 - eta) + unit.scaled(eta)
            models[a] = maximise(mean[a].scaled(total[a]), models[a], SMALL.covar_reg)
        else:
            buf[a].append(X)
            if len(buf[a]) >= 3:
                m = train(buf[a], cfg, weights=np.ones(len(buf[a])), seed=2, warn=False).model
                models[a] = GMMHMMParams(m.startprob, m.transmat, m.weights, m.means, m.covars)
                stats = expected_stats(buf[a], models[a])
                mean[a], total[a] = stats.scaled(1 / float(stats.weight)), float(stats.weight)
    for a in range(3):
        np.testing.assert_allclose(run.params.means[0, a], models[a].means, rtol=1e-8, atol=1e-10)
        np.testing.assert_allclose(run.params.covars[0, a], models[a].covars, rtol=1e-8, atol=1e-10)


def test_learners_in_lockstep_learn_what_each_learns_alone(engine):
    ep, held, p = _stream(engine, 40)
    actions = engine.bn.schema.values_of("Action")
    settings = ol.OnlineSettings(config=SMALL, cluster_episodes=9)
    rnd = ss.matched_random_labels(ep.actions, 0.6, 3, np.random.default_rng(1))
    learners = [
        ol.Learner("soft", "n"),
        ol.Learner("iterative", "n"),
        ol.Learner("true"),
        ol.Learner("unsupervised"),
        ol.Learner("random", "r"),
        ol.Learner("clustering", "n"),
        ol.Learner("em", "n"),
        ol.Learner("supervised", 2),
    ]
    args = (held.features, held.actions, [20, 40], actions, settings, 0)
    together = ol.run_online(ep.features, ep.actions, learners, {"n": p, "r": rnd}, *args)
    for k, lr in enumerate(learners):
        alone = ol.run_online(ep.features, ep.actions, [lr], {"n": p, "r": rnd}, *args)
        np.testing.assert_array_equal(together.correct[:, k], alone.correct[:, 0])
        np.testing.assert_allclose(together.params.means[k], alone.params.means[0], rtol=1e-10)
        np.testing.assert_allclose(together.weights[:, k], alone.weights[:, 0], rtol=1e-10)


def test_online_learning_from_true_labels_recognises_held_out_gestures(engine):
    ep, held, p = _stream(engine, 60, seed=1, test=30)
    actions = engine.bn.schema.values_of("Action")
    run = ol.learn_online(
        ep.features,
        ep.actions,
        "true",
        None,
        actions,
        ol.OnlineSettings(config=SMALL),
        0,
        held.features,
        held.actions,
        [60],
    )
    assert run.accuracy()[-1, 0] >= 0.8
    rec = run.recognizer(0)
    assert rec.actions == tuple(actions) and rec.meta["scheme"] == "true"
    pred = [rec.classify(x) for x in held.features]
    assert (
        np.mean([pr == actions[a] for pr, a in zip(pred, held.actions, strict=True)]) == run.accuracy()[-1, 0]
    )


def test_the_first_episodes_are_labelled_by_the_network_alone(engine):
    ep = ss.simulate_episodes(engine, ss.AMBIGUITIES["mixed"], 30, 0)
    p = ss.network_posteriors(engine, ep.perceived, ep.world)  # without words: uncertain labels
    actions = engine.bn.schema.values_of("Action")
    run = ol.learn_online(ep.features, ep.actions, "iterative", p, actions, ol.OnlineSettings(config=SMALL))
    np.testing.assert_allclose(run.weights[:5, 0], p[:5])  # no gesture model yet: the network alone
    assert not np.allclose(run.weights[-10:, 0], p[-10:])  # later: the product with its HMMs


def test_learners_that_must_coincide(engine):
    """Clusters named by certain labels are the clusters named by the truth; random labels that are one-hot
    are hard labels of the same matrix; semi-supervised EM with certain labels is the true-label learner."""
    ep, held, _ = _stream(engine, 36)
    actions = engine.bn.schema.values_of("Action")
    certain = ss.one_hot(ep.actions, 3)
    learners = [
        ol.Learner("clustering", "c"),
        ol.Learner("unsupervised"),
        ol.Learner("random", "c"),
        ol.Learner("hard", "c"),
        ol.Learner("em", "c"),
        ol.Learner("true"),
    ]
    settings = ol.OnlineSettings(config=SMALL, cluster_episodes=9)
    run = ol.run_online(
        ep.features,
        ep.actions,
        learners,
        {"c": certain},
        held.features,
        held.actions,
        [36],
        actions,
        settings,
    )
    for a, b in ((0, 1), (2, 3), (4, 5)):
        np.testing.assert_array_equal(run.matching[:, a], run.matching[:, b])
        np.testing.assert_allclose(run.params.means[a], run.params.means[b], rtol=1e-10)
        np.testing.assert_array_equal(run.correct[:, a], run.correct[:, b])


def test_supervision_by_one_label_per_action_is_one_training(engine):
    """``supervised`` with 1 label per action: each model trained on its action's first episode alone, then
    never updated."""
    ep, held, _ = _stream(engine, 30)
    actions = engine.bn.schema.values_of("Action")
    settings = ol.OnlineSettings(config=SMALL, init_iter=5)
    calls = []
    run = ol.run_online(
        ep.features,
        ep.actions,
        [ol.Learner("supervised", 1)],
        {},
        held.features,
        held.actions,
        [30],
        actions,
        settings,
        seed=4,
        progress=calls.append,
    )
    assert calls == ["episode"] * 30  # one call per episode
    one = ol.learn_online(ep.features, ep.actions, "supervised", None, actions, settings, 4, per_action=1)
    for a in range(3):
        first = ep.features[int(np.flatnonzero(ep.actions == a)[0])]
        m = train([first], SMALL.replace(n_iter=5), weights=np.ones(1), seed=4, warn=False).model
        np.testing.assert_allclose(run.params.means[0, a], m.means, rtol=1e-8, atol=1e-10)
        np.testing.assert_allclose(one.params.means[0, a], m.means, rtol=1e-8, atol=1e-10)  # one learner
    assert np.count_nonzero(run.weights[:, 0]) == 3
    with pytest.raises(DataError, match="labels per action None"):  # learn_online needs per_action
        ol.learn_online(ep.features, ep.actions, "supervised", None, actions, settings)
    with pytest.raises(DataError, match="labels per action"):
        ol.run_online(
            ep.features,
            ep.actions,
            [ol.Learner("supervised", 0)],
            {},
            held.features,
            held.actions,
            [30],
            actions,
        )


@pytest.mark.parametrize(
    ("bad", "message"),
    [
        ({"step": 0.3}, "step"),
        ({"posterior": "vote"}, "posterior"),
        ({"init_weight": 0}, "init_weight=0: a number > 0"),
        ({"init_iter": 0}, "init_iter=0: a whole number ≥ 1"),
        ({"cluster_episodes": 2}, "cluster_episodes=2: a whole number ≥ 3"),
    ],
)
def test_online_settings_are_checked(bad, message):
    with pytest.raises(DataError, match=message):
        ol.OnlineSettings(**bad)


@pytest.mark.parametrize(
    ("learner", "checkpoints", "message"),
    [
        (ol.Learner("guess", "n"), [2], "unknown learner 'guess'; allowed: "),
        (ol.Learner("soft", "x"), [2], "learner 'soft': no network posteriors for 'x'"),
        (ol.Learner("true"), [3], "checkpoints must lie in 1 … 2 \\(the episodes\\), got \\[3\\]"),
        (ol.Learner("true"), [], "checkpoints must lie in 1 … 2"),
    ],
)
def test_bad_learners_and_checkpoints_are_refused(learner, checkpoints, message):
    xs = [np.zeros((5, 3))] * 2
    p = {"n": np.full((2, 3), 1 / 3)}
    with pytest.raises(DataError, match=message):
        ol.run_online(xs, np.zeros(2, int), [learner], p, xs, np.zeros(2, int), checkpoints, ("a", "b", "c"))


def test_the_recording_of_an_online_learner_reads_back(engine, tmp_path):
    import subprocess
    import sys

    import pyarrow as pa
    import rerun as rr
    from rerun.chunk import RrdReader

    from glu.studies.learning.recordings import write_learning

    ep, held, p = _stream(engine, 24, test=6)
    actions = engine.bn.schema.values_of("Action")
    run = ol.learn_online(
        ep.features,
        ep.actions,
        "soft",
        p,
        actions,
        ol.OnlineSettings(config=SMALL),
        0,
        held.features,
        held.actions,
        [8, 16, 24],
    )
    rr.set_strict_mode(True)
    try:
        path = write_learning(run, ep.features, tmp_path / "l.rrd", "test-learning", scene="# learning")
    finally:
        rr.set_strict_mode(False)
    res = subprocess.run(
        [sys.executable, "-m", "rerun", "rrd", "verify", str(path)], capture_output=True, text=True
    )
    assert res.returncode == 0, res.stderr

    def column(entity, component):
        stream = RrdReader(str(path)).stream().filter(content=entity, is_static=False, components=component)
        batches = [c.to_record_batch().select(["episode", component]) for c in stream]
        return pa.Table.from_batches(batches).sort_by("episode")

    tap = column("/labels/tap", "Scalars:scalars")
    assert tap.column("episode").to_pylist() == list(range(1, 25))
    np.testing.assert_allclose(
        [v[0] for v in tap.column("Scalars:scalars").to_pylist()], run.weights[:, 0, 1]
    )
    acc = column("/accuracy/held-out", "Scalars:scalars")
    assert acc.column("episode").to_pylist() == [8, 16, 24]
    np.testing.assert_allclose(
        [v[0] for v in acc.column("Scalars:scalars").to_pylist()], run.accuracy()[:, 0]
    )
    path_tap = column("/space/models/tap/path", "LineStrips3D:strips")
    last = np.array(path_tap.column("LineStrips3D:strips").to_pylist()[-1][0])
    np.testing.assert_allclose(last, run.means[-1, 0, 1], rtol=1e-6)
    texts = column("/decisions", "TextLog:text").column("TextLog:text").to_pylist()
    assert len(texts) == 24 and texts[0][0].startswith("episode 1: ")


def test_the_recorded_life_is_the_scheme_and_the_true_labels_on_the_same_episodes(engine):
    """Notebook 12's recorded learner: the scheme labelling by the network (no words) and the true labels,
    run together on the same episodes, measured every 10 on balanced held-out gestures, as by hand."""
    settings = ol.OnlineSettings(config=SMALL)
    life = lr_.recorded_life(engine, "soft", 25, 2, seed=1, settings=settings)
    amb = ss.AMBIGUITIES["mixed"]
    ep = ss.simulate_episodes(engine, amb, 25, 1)
    held = ss.simulate_episodes(engine, amb, 6, 1, offset=ss.TEST_OFFSET, balanced=True)
    p = ss.network_posteriors(engine, ep.perceived, ep.world)
    learners = [ol.Learner("soft", "network"), ol.Learner("true")]
    actions = engine.bn.schema.values_of("Action")
    by_hand = ol.run_online(
        ep.features, ep.actions, learners, {"network": p}, held.features, held.actions, [10, 20], actions,
        settings, 1,
    )  # fmt: skip
    assert list(life.run.checkpoints) == [10, 20] and life.run.learners == learners
    np.testing.assert_array_equal(life.run.correct, by_hand.correct)
    np.testing.assert_array_equal(life.run.weights, by_hand.weights)
    assert len(life.features) == 25 and life.held_out == 6 == len(held.features)
    acc = by_hand.accuracy()[-1]
    assert life.summary() == (
        f"after 25 episodes: soft labels {acc[0]:.3f}, true labels {acc[1]:.3f} on 6 held-out gestures"
    )
    assert life.scene() == f"# Learning gestures from effects\nsoft labels, {amb.description}; 25 episodes."
    assert list(life.recognizers()) == ["soft labels", "true labels"]
    assert life.recognizers()["true labels"].meta["scheme"] == "true"
