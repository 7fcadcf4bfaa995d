"""Thermal simulator, parameter screening (thesis 3.2, fig. 3-5) and the thesis-like experiment
(tables 5-1, 5-2): table 5-2 over 6 seeds of the realistic preset compared with the thesis's
printed runs, the screening's mechanics on synthetic problems with a known answer, and its
stability over resamples. Everything seeded."""

import math

import numpy as np
import pytest

from robocal.io.thermal_files import read_run
from robocal.robots import load_robot
from robocal.sim.thermal.simulator import (
    ProductionSchedule,
    ThermalCell,
    standard_schedules,
    write_run,
)
from robocal.thermal import identify_drift
from robocal.thermal.screening import (
    ScreeningProblem,
    direction_residuals,
    lambda_metric,
    sample_autocorrelation,
    screen_parameters,
    select_online_poses,
    stationarity_test,
    traditional_parameters,
)
from robocal.workflows.thermal.runs import format_thermal_report, format_thermal_table, run_thermal_experiment, \
    screening_problem


@pytest.fixture(scope="module")
def experiment():
    return run_thermal_experiment()


@pytest.fixture(scope="module")
def cell():
    return ThermalCell.standard(2024)


# ------------------------------------------------------------------------------------------ table 5-2
# The thesis's table 5-2 (../shared/seeds/thesis-accuracy-maintenance.zh.md, 5.1.3; METHODS.md 4):
# share [%] of monitored directions whose residual is better than 0.1 mm, three test runs of one
# KR150 R3100 after screening on a separate long run (so all three are evaluation runs), 90 cycles.
THESIS_TABLE_5_2 = {"before": (43.18, 49.41, 48.05), "traditional": (73.86, 80.00, 87.01),
                    "screened": (90.91, 96.47, 94.81)}
# and the thesis's selection (5.1.2; one of its eight names is lost in the extraction: "a3, a3")
THESIS_SELECTED = {"d4", "d6", "a1", "a2", "a3", "a4", "beta2"}


@pytest.fixture(scope="module")
def seeds():
    """Table 5-2 on the realistic preset in the thesis's setting (90 cycles per run) over 6 seeds
    (12 evaluation runs; ~15 s, the 20-seed table is ``robocal thermal experiment``, docs/thermal.md)."""
    from robocal.workflows.thermal.seeds import run_thermal_seeds

    return run_thermal_seeds(preset="realistic", seeds=6, first_seed=1, n_cycles=90)


def thesis_band(column):
    """The thesis's three runs widened on each side by their own spread (max - min): a simulated
    cell is another robot in another hall, and cannot be expected to agree with the thesis closer
    than the thesis's runs agree with one another."""
    lo, hi = min(THESIS_TABLE_5_2[column]), max(THESIS_TABLE_5_2[column])
    return lo - (hi - lo), min(hi + (hi - lo), 100.0)


def test_table_5_2_medians_within_the_thesis_range(seeds):
    """The median over the evaluation runs of each column lies in the thesis's band (before
    36.95-55.64 %, traditional 60.71-100 %, screened 85.35-100 %). It fails when the drift, the
    compensation or the screening regress to another level (e.g. a screening that picks the
    traditional set, ~73 %, or a sign error in the compensation, at or below "before").
    Measured, seeds 1-6 (thesis statistic): 41.7 / 72.1 / 95.6; seeds 7-12 and 13-18: before 41.7
    and 43.6, traditional 74.5 and 71.1, screened 96.1 and 95.6."""
    t = seeds["tables"]["rms"]["evaluation"]
    for column in THESIS_TABLE_5_2:
        lo, hi = thesis_band(column)
        assert lo <= t[column]["median"] <= hi, (column, t[column]["median"], (lo, hi))


def test_table_5_2_ordering_over_seeds(seeds):
    """The thesis's finding, screened > traditional > before in each of its three runs: in the
    medians of both statistics and both roles, and per run in at least 80 % of the evaluation runs
    with the thesis's statistic (measured 100 %); with the strict statistic (every cycle within
    0.1 mm, not the thesis's) in more than half of them (measured 75-100 % over three groups of 6
    seeds)."""
    for st in ("rms", "max"):
        for role in ("screening", "evaluation"):
            t = seeds["tables"][st][role]
            assert t["screened"]["median"] > t["traditional"]["median"] > t["before"]["median"], (st, role)
            for c in ("before", "traditional", "screened"):
                assert t[c]["q25"] <= t[c]["median"] <= t[c]["q75"] and t[c]["n"] == (6 if role == "screening" else 12)
    assert seeds["ordering"]["rms"]["evaluation"]["strict_order"] >= 0.8
    assert seeds["ordering"]["max"]["evaluation"]["strict_order"] > 0.5
    # a direction that never left the band has an rms below it: the strict share is never larger
    for s in seeds["per_seed"]:
        for r in s["rows"]:
            assert all(r["lambda"]["max"][c] <= r["lambda"]["rms"][c] for c in ("before", "traditional", "screened"))


def test_selection_over_seeds_agrees_with_the_thesis(seeds):
    """Every seed selects 8 parameters, so the frequencies add up to 8. The thesis's finding
    (5.1.2): heat moves only some parameters, and not only the non-zero lengths -- every seed's
    set holds a parameter outside the traditional set; the parameter selected most often is one
    the thesis selected, and more than half of the thesis's set is selected in at least half of
    the seeds (measured over three groups of 6 seeds: a2 first every time, 4-5 of the thesis's 7
    in at least half of the seeds)."""
    f = seeds["selection"]
    assert sum(f.values()) == pytest.approx(8.0)
    assert list(f.values()) == sorted(f.values(), reverse=True)
    assert next(iter(f)) in THESIS_SELECTED
    assert sum(f.get(n, 0.0) >= 0.5 for n in THESIS_SELECTED) > len(THESIS_SELECTED) / 2
    traditional = set(traditional_parameters(load_robot("kuka_kr150_r3100")))
    assert all(set(s["screened"]) - traditional for s in seeds["per_seed"])


def test_experiment_structure(experiment):
    """The thesis's setting, both statistics per column and the schedules differing (one seed of
    the ideal preset; the figures themselves are the multi-seed tests above)."""
    rows = experiment["rows"]
    assert [r["run"] for r in rows] == [1, 2, 3] and [r["role"] for r in rows] == ["screening", "evaluation",
                                                                                  "evaluation"]
    s = experiment["settings"]
    assert (s["n_screen_poses"], s["n_online_poses"], s["n_monitored_points"], s["n_cycles"]) == (20, 6, 34, 90)
    assert s["preset"] == "ideal"
    assert experiment["screening"].steps[0].n_params == 24 and len(experiment["screened"]) == 8
    assert all(len(v) == 6 for v in experiment["online_poses"].values())
    assert experiment["traditional"] == ("d1", "a1", "a2", "a3", "d4", "d6")
    for r in rows:
        assert r["lambda"]["rms"] == {k: r[k] for k in ("before", "traditional", "screened")}
        assert all(r["lambda"]["max"][k] <= r["lambda"]["rms"][k] for k in r["lambda"]["max"])
    sch = [r.schedule for r in experiment["runs"]]
    assert not np.allclose(sch[0].idle_s, sch[1].idle_s) and not np.allclose(sch[1].load, sch[2].load)


def test_tables_render(experiment):
    text = format_thermal_table(experiment)
    assert "traditional" in text and "screened" in text and len(text.splitlines()) == 2 + 3 + 2
    rep = format_thermal_report(experiment)
    assert "parameter screening" in rep and "selected (8)" in rep
    tab = experiment["screening"].table()
    assert [t["n_params"] for t in tab] == list(range(24, 7, -1))
    assert tab[0]["removed"] == "-" and all(t["removed"] != "-" for t in tab[1:])


# ------------------------------------------------------------------------------------------ lambda
def test_lambda_metric_hand_computed():
    # 2 cycles x 2 points x (x, y, z) [mm]
    r = np.array([[[0.05, 0.20, 0.00], [0.09, -0.12, 0.30]],
                  [[0.05, 0.00, 0.13], [-0.11, 0.05, 0.00]]])
    # RMS per direction: 0.05, 0.1414, 0.0919 | 0.1005, 0.0919, 0.2121 -> below 0.1: 0.05, 0.0919, 0.0919
    rms = direction_residuals(r, "rms")
    np.testing.assert_allclose(rms, [[0.05, math.sqrt(0.02), math.sqrt(0.0169 / 2)],
                                     [math.sqrt((0.0081 + 0.0121) / 2), math.sqrt(0.0169 / 2), math.sqrt(0.045)]])
    assert lambda_metric(r) == pytest.approx(50.0)
    # max |r|: 0.05, 0.2, 0.13 | 0.11, 0.12, 0.3 -> only the first direction is below 0.1
    assert lambda_metric(r, statistic="max") == pytest.approx(100.0 / 6)
    assert lambda_metric(r, threshold_mm=0.2) == pytest.approx(500.0 / 6)      # all but 0.2121
    assert lambda_metric(r.reshape(2, 6)) == pytest.approx(50.0)
    with pytest.raises(ValueError, match="unknown statistic"):
        lambda_metric(r, statistic="median")


# ------------------------------------------------------------------------------------------ stationarity
def test_sample_autocorrelation_definition():
    x = np.random.default_rng(3).normal(size=50)
    r = sample_autocorrelation(x, 5)
    d = x - x.mean()
    expect = [np.sum(d[: 50 - k] * d[k:]) / np.sum(d * d) for k in range(6)]
    np.testing.assert_allclose(r, expect)
    assert sample_autocorrelation(np.ones(10), 3).tolist() == [1.0, 0.0, 0.0, 0.0]


def test_white_noise_is_stationary():
    rng = np.random.default_rng(11)
    res = stationarity_test(rng.normal(size=90))
    assert res.stationary and res.inside_share >= 0.8
    assert res.band == pytest.approx(1.96 * math.sqrt((1 + 2 * res.acf[1] ** 2) / 90))     # Bartlett, MA(1)
    assert res.tested.tolist() == list(range(2, 16))
    many = stationarity_test(rng.normal(size=(300, 90)))
    assert many.mean() >= 0.95
    # a stationary AR(1) with short memory (phi = 0.3) passes as well
    e = rng.normal(size=(300, 90))
    ar = np.zeros_like(e)
    for t in range(1, 90):
        ar[:, t] = 0.3 * ar[:, t - 1] + e[:, t]
    assert stationarity_test(ar).mean() >= 0.85


def test_trend_and_random_walk_are_not_stationary():
    rng = np.random.default_rng(12)
    t = np.arange(90)
    assert not stationarity_test(0.01 * t + rng.normal(0, 0.1, 90)).stationary          # linear trend
    heating = 1.0 - np.exp(-t / 20.0)                                                        # first-order heating
    assert not stationarity_test(heating + rng.normal(0, 0.1, 90)).stationary
    assert not stationarity_test(np.cumsum(rng.normal(size=90))).stationary                 # random walk
    walks = np.cumsum(rng.normal(size=(300, 90)), axis=1)
    assert (~stationarity_test(walks)).mean() >= 0.9
    trends = 0.01 * t + rng.normal(0, 0.1, (300, 90))
    assert (~stationarity_test(trends)).mean() >= 0.99


# ------------------------------------------------------------------------------------------ greedy
def _synthetic(seed=5, C=60, m=10, K=12, F=7, drifting=(0, 2, 5), noise=0.01):
    rng = np.random.default_rng(seed)
    M = rng.normal(size=(m, 3, F))
    J = rng.normal(size=(K, 3, F))
    t = np.arange(C)
    dX = np.zeros((C, F))
    for j, k in enumerate(drifting):
        dX[:, k] = (0.1 + 0.05 * j) * (1.0 - np.exp(-t / (10.0 + 5 * j)))
    Y = np.einsum("mif,cf->cmi", M, dX) + rng.normal(0, noise, (C, m, 3))
    before = -np.einsum("kif,cf->cki", J, dX) + rng.normal(0, noise, (C, K, 3))
    return ScreeningProblem(tuple(f"p{i}" for i in range(F)), M, Y, J, before), dX


def test_greedy_elimination_finds_the_drifting_parameters():
    prob, dX = _synthetic()
    res = screen_parameters(prob, 3, threshold_mm=0.05)
    assert set(res.selected) == {"p0", "p2", "p5"}
    assert [s.n_params for s in res.steps] == [7, 6, 5, 4, 3]
    # the non-drifting parameters are stationary and are removed first; the drifting ones never are
    assert set(res.steps[0].stationary) == {"p1", "p3", "p4", "p6"}
    assert set(res.removed) == {"p1", "p3", "p4", "p6"}
    assert res.lam == pytest.approx(100.0)
    # identified deltas of the final set follow the truth
    d = prob.identify(res.selected)
    np.testing.assert_allclose(d, dX[:, [0, 2, 5]], atol=0.02)
    # a set missing a drifting parameter scores worse
    assert prob.evaluate(("p0", "p2", "p3"), 0.05).lam < res.lam
    assert prob.evaluate((), 0.05).lam < 50.0


def test_greedy_falls_back_to_all_parameters_when_none_is_stationary():
    # every parameter drifts: S is empty, the best removal over all is taken
    prob, _ = _synthetic(seed=6, F=4, drifting=(0, 1, 2, 3))
    res = screen_parameters(prob, 2, threshold_mm=0.05)
    assert res.steps[0].stationary == () and res.steps[1].fallback
    assert len(res.steps[1].candidates) == 4


# ------------------------------------------------------------------------------------------ problem
def test_traditional_set_of_the_kr150():
    assert traditional_parameters(load_robot("kuka_kr150_r3100")) == ("d1", "a1", "a2", "a3", "d4", "d6")


def test_batched_identification_matches_identify_drift(experiment):
    cell, run, prob = experiment["cell"], experiment["runs"][1], experiment["problems"][1]
    calib = experiment["system_calibration"]
    names = experiment["screened"]
    idx = experiment["online_poses"]["screened"]
    d = prob.with_poses(idx).identify(names)
    for c in (10, 60):
        ref = identify_drift(cell.model, calib.T_sensor_base, calib.P_e, run.q_sphere[idx], run.sphere[c, idx],
                             run.sphere_cold[idx], names)
        np.testing.assert_allclose(d[c], ref.delta, rtol=1e-7, atol=1e-12)


def test_compensated_residual_matches_recomputed_points(experiment):
    """r_ck = X_ck(dX_c) - X_k,cold: the first-order residual equals the points recomputed with the
    warm parameter vector by full forward kinematics."""
    cell, run, prob = experiment["cell"], experiment["runs"][0], experiment["problems"][0]
    names = experiment["screened"]
    model = cell.model
    c = 70
    d = prob.identify(names)[c]
    X = model.params.values.copy()
    for n, v in zip(names, d):
        X[model.params.index(n)] += v
    warm = model.with_params(X)
    Tfs = cell.T_flange_sensor

    def points(mdl, meas):
        T = mdl.fk(run.q_monitor) @ Tfs
        return np.einsum("kij,kj->ki", T[:, :3, :3], meas) + T[:, :3, 3]

    exact = points(warm, run.monitor[c]) - points(model, run.monitor_cold)
    np.testing.assert_allclose(prob.residuals(names)[c], exact, atol=5e-4)          # second order: < 0.5 um


def test_online_pose_selection(experiment):
    prob = experiment["problems"][0]
    names = experiment["screened"]
    idx = select_online_poses(prob, names, 6)
    assert len(idx) == 6 and len(set(idx.tolist())) == 6 and np.all(np.diff(idx) > 0)
    assert prob.with_poses(idx).evaluate(names).lam >= prob.with_poses(np.arange(6)).evaluate(names).lam - 1e-9
    with pytest.raises(ValueError, match="at least 3 poses"):
        select_online_poses(prob, names, 2)
    with pytest.raises(KeyError, match="candidate"):
        prob.columns(["beta3"])


def test_screening_is_deterministic(experiment):
    """Screening the same problem again gives the same set (speed: benchmarks/bench_thermal.py)."""
    prob = experiment["problems"][0]
    res = screen_parameters(prob)
    assert res.selected == experiment["screened"]
    assert [s.lam for s in res.steps] == [s.lam for s in experiment["screening"].steps]


# ------------------------------------------------------------------------------------------ simulator
def test_drift_after_three_hours_of_production(cell):
    sched = ProductionSchedule(np.full(60, 140.0), np.full(60, 1.0), np.zeros(60))       # 3 h non-stop
    assert sched.duration_s == pytest.approx(3 * 3600.0)
    run = cell.simulate(sched, 1)
    tcp = np.interp(3 * 3600.0, run.timeline_s, run.tcp_drift_mm)
    assert 0.1 <= tcp <= 0.5
    assert run.tcp_drift_mm[0] == 0.0
    # monitored points drift 0.1-0.5 mm (3-D) at the end, directions in between
    drift = np.linalg.norm(run.monitor[-1] - run.monitor_cold, axis=1)
    assert 0.1 <= np.median(drift) <= 0.5
    # joints 2-4 are the heaviest heat sources
    h = run.states[-1]
    assert set(np.argsort(h)[-3:]) == {1, 2, 3}
    # the drift direction is nearly fixed: late drifts are nearly parallel to the final one
    d = run.delta_true[len(run.delta_true) // 3:]
    cos = d @ d[-1] / (np.linalg.norm(d, axis=1) * np.linalg.norm(d[-1]))
    assert cos.min() > 0.98


def test_cooling_when_idle(cell):
    sched = ProductionSchedule(np.full(40, 140.0), np.full(40, 1.0), np.r_[np.zeros(39), 3 * 3600.0])
    th = cell.thermal
    end = sched.start_s[-1] + 140.0 + sched.measure_s
    t = end + np.linspace(0.0, 3 * 3600.0, 50)
    h = th.states(sched, t)
    assert np.all(np.diff(h, axis=0) < 0)                            # cooling, every source
    # first order: h(t) = h(end) exp(-(t - end) / tau)
    np.testing.assert_allclose(h, h[0] * np.exp(-(t - end)[:, None] / th.taus), rtol=1e-10)
    assert np.all(h[-1] < 0.1 * h[0])
    # heating: with constant load the state approaches the gain times the load monotonically
    hh = th.states(ProductionSchedule(np.full(1, 20 * 3600.0), np.ones(1), np.zeros(1)), [3600.0, 7200.0, 72000.0])
    assert np.all(np.diff(hh, axis=0) > 0)
    np.testing.assert_allclose(hh[-1], th.gains * np.array([0.6, 1.0, 0.9, 0.8, 0.5, 0.5]), rtol=1e-6)


def test_simulation_is_seeded_and_schedules_differ(cell):
    s1, s2, s3 = standard_schedules(7)
    a, b = cell.simulate(s1, 5), cell.simulate(s1, 5)
    np.testing.assert_array_equal(a.sphere, b.sphere)
    np.testing.assert_array_equal(a.monitor, b.monitor)
    assert not np.array_equal(cell.simulate(s1, 6).sphere, a.sphere)
    assert s1.n_cycles == s2.n_cycles == s3.n_cycles == 90
    assert 150 <= np.median(s1.work_s + s1.measure_s) <= 190
    assert s2.idle_s.max() >= 2700.0 and s3.idle_s.max() >= 1800.0
    assert len(cell.q_sphere) == 20 and len(cell.q_monitor) == 34
    ext = cell.body_points.max(0) - cell.body_points.min(0)
    assert 800 <= ext[0] <= 1200 and 1300 <= ext[1] <= 1700
    with pytest.raises(TypeError):
        cell.simulate(s1, None)


def test_run_files_round_trip(cell, tmp_path):
    sched = ProductionSchedule.generate(3, 5)
    run = cell.simulate(sched, 3)
    paths = write_run(tmp_path / "run", cell, run)
    assert {"sphere", "sphere_cold", "monitor", "monitor_cold", "cycles", "truth"} <= set(paths)
    back = read_run(tmp_path / "run", robot=cell.model)
    np.testing.assert_array_equal(back["sphere"], run.sphere)
    np.testing.assert_array_equal(back["monitor_cold"], run.monitor_cold)
    np.testing.assert_allclose(back["q_sphere"], run.q_sphere, atol=1e-12)
    np.testing.assert_allclose(back["times_s"], run.times_s)
    with pytest.raises(FileExistsError):
        write_run(tmp_path / "run", cell, run)
    # the screening problem from the files equals the one from the arrays
    p1 = screening_problem(cell, run)
    p2 = ScreeningProblem.from_measurements(cell.model, cell.T_sensor_base, cell.P_e, back["q_sphere"],
                                            back["sphere_cold"], back["sphere"], back["q_monitor"],
                                            back["monitor_cold"], back["monitor"], cell.T_flange_sensor)
    np.testing.assert_allclose(p1.before, p2.before, atol=1e-9)


# ------------------------------------------------------------------------------------------ stability
def test_selection_frequency_hand_case():
    from robocal.thermal.stability import selection_frequency

    f = selection_frequency([("a", "b"), ("b", "c"), ("b", "a"), ("d", "b")])
    assert f == {"b": 1.0, "a": 0.5, "c": 0.25, "d": 0.25}
    assert selection_frequency([("a",)], names=("z", "a")) == {"z": 0.0, "a": 1.0}
    with pytest.raises(ValueError, match="no sets"):
        selection_frequency([])


def test_resampled_cycles_keep_time_order():
    from robocal.thermal.stability import resample_cycles

    idx = resample_cycles(50, 3)
    assert len(idx) == 50 and np.all(np.diff(idx) >= 0) and idx.min() >= 0 and idx.max() < 50
    assert len(np.unique(idx)) < 50                                        # drawn with replacement
    np.testing.assert_array_equal(idx, resample_cycles(50, 3))


def test_stability_of_a_clear_screening():
    """Three parameters drift, four do not: every resample keeps the three."""
    from robocal.thermal.stability import screening_stability

    prob, _ = _synthetic()
    rep = screening_stability(prob, 20, 4, n_keep=3, threshold_mm=0.05)
    assert rep.n_resamples == 20 and rep.agreement == 1.0
    assert set(rep.selected) == set(rep.full) == {"p0", "p2", "p5"}
    assert [rep.frequency[n] for n in ("p0", "p2", "p5")] == [1.0, 1.0, 1.0] and rep.unstable() == []
    assert [r["name"] for r in rep.table()][:3] == ["p0", "p2", "p5"]


def test_stability_exposes_interchangeable_parameters():
    """p6 does not drift but is a near copy of p5 (columns 0.5 % apart): the full run keeps one
    of the two, and which one survives depends on the cycles (both between 20 and 80 % of 30
    resamples; measured 57 / 43 %); p0 and p2 are kept by every resample."""
    from robocal.thermal.stability import screening_stability

    rng = np.random.default_rng(8)
    prob, dX = _synthetic(seed=8)
    M = prob.M.copy()
    M[:, :, 6] = M[:, :, 5] + 0.005 * rng.normal(size=M[:, :, 5].shape)
    J = prob.J.copy()
    J[:, :, 6] = J[:, :, 5] + 0.005 * rng.normal(size=J[:, :, 5].shape)
    Y = np.einsum("mif,cf->cmi", M, dX) + rng.normal(0, 0.05, prob.Y.shape)
    before = -np.einsum("kif,cf->cki", J, dX) + rng.normal(0, 0.05, prob.before.shape)
    p2 = ScreeningProblem(prob.names, M, Y, J, before)
    rep = screening_stability(p2, 30, 2, n_keep=3, threshold_mm=0.08)
    assert rep.frequency["p0"] == 1.0 and rep.frequency["p2"] == 1.0
    # which of the near copies the full run keeps is arbitrary (measured: p6); p0 and p2 are not
    assert rep.full[:2] == ("p0", "p2") and rep.full[2] in {"p5", "p6"}
    assert 0.2 < rep.frequency["p5"] < 0.8 and 0.2 < rep.frequency["p6"] < 0.8
    assert rep.frequency["p5"] + rep.frequency["p6"] == pytest.approx(1.0)
    assert 0.2 < rep.agreement < 0.8 and set(rep.unstable()) == {"p5", "p6"}
    assert {"p0", "p2"} <= set(rep.selected) and len(rep.selected) == 3


def test_online_poses_for_a_set_no_subset_identifies(experiment):
    """All four parameters of the last link seen through one sphere centre: the strict design
    finds no identifying subset and falls back to the poses of highest rank (3 of 4 combinations)
    with the least min-norm noise."""
    from robocal.thermal.online_poses import _i_optimal_cost

    prob = experiment["problems"][0]
    names = ("a2", "d4", "theta6", "d6", "a6", "alpha6")
    idx = select_online_poses(prob, names, 6)
    assert len(idx) == 6 and np.all(np.diff(idx) > 0)
    cols = prob.columns(names)
    A = prob._An[:, cols].reshape(prob.n_poses, 3, len(cols))
    info = np.einsum("pik,pil->pkl", A, A)
    N = info[idx].sum(axis=0)
    assert np.linalg.matrix_rank(N, tol=1e-10 * np.linalg.norm(N, 2)) == len(names) - 1
    strict = _i_optimal_cost(info, np.eye(len(cols)), idx[None])
    assert np.isinf(strict[0])
