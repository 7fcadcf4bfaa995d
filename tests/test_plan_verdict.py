"""Issue 28, item 4: one identifiability verdict. The planner predicts what the calibration reports:
on the same 40 poses (reflector on the joint-6 axis, where the nominal geometry alone hides a5 and
alpha5), plan-poses and the calibration of simulated robots name the same identifiable set, and
the planner's sigma for a weakly identified parameter is what the calibration reports."""

from __future__ import annotations

from robocal.workflows.calibration.plan_verdict import plan_and_calibrations


def test_plan_and_calibration_agree_on_the_same_40_poses():
    plan, results = plan_and_calibrations((11, 12, 13))
    predicted = set(plan["identifiable"])
    for res in results:
        got = {n.replace("point.", "reflector.") for n in res.identifiability.identifiable}
        assert got == predicted, (sorted(got ^ predicted))
        # a5 rests on the sub-mm lever a real robot's deviations give: sigma of mm, in both
        s_plan = plan["std"][plan["names"].index("a5")]
        s_cal = res.std[res.names.index("a5")]
        assert s_plan > 0.5 and 1 / 3 < s_cal / s_plan < 3, (s_plan, s_cal)
