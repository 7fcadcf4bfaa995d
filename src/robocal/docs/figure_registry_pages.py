"""Registered figures of docs/iso9283.md, reliability.md, robots.md, fleet.md, thermal.md and smaller pages.

The registry (:mod:`robocal.docs.figure_registry`) appends them; producers: :mod:`robocal.docs.figure_producers_pages`
unless named otherwise."""

from __future__ import annotations

from .figure_registry import _N, Figure, _cell

__all__ = ["PAGE_FIGURES"]

PAGE_FIGURES: list = []

# ---- docs/iso9283.md ----
_ISO = "docs/iso9283.md"
_BL = r"Measured \(`tests/test_verify\.py`, IRB 140, 10 poses with random approach sides(?s:.*?)"
_BC = r"moved by ±0\.075° by approach side\): "
PAGE_FIGURES += [Figure(f"iso9283:{k}", _ISO, pat, prod, field, rel_tol=tol)
                 for k, pat, prod, field, tol in (
                     ("adequacy RP low", r"inadequate for every RP \(≈ " + _N, "iso9283/adequacy", "RP.min", 0.0),
                     ("adequacy RP high", r"inadequate for every RP \(≈ [0-9.]+–" + _N, "iso9283/adequacy", "RP.max",
                      0.0),
                     ("backlash detected", _BL + r"is detected in " + _N + " %", "iso9283/verify_backlash_trials",
                      "detected.min", 0.0),
                     ("backlash named low", _BL + r"backlash in " + _N + "–", "iso9283/verify_backlash_trials",
                      "named.min", 0.0),
                     ("backlash named high", _BL + r"backlash in [0-9]+–" + _N + " %", "iso9283/verify_backlash_trials",
                      "named.max", 0.0),
                     ("backlash offset stays offset", _BL + r"stays an offset in " + _N + " %",
                      "iso9283/verify_backlash_trials", "offset_named.min", 0.0),
                     ("verify T", _BC + r"T = " + _N, "iso9283/verify_backlash_command", "T", 0.01),
                     ("verify threshold", _BC + r"T = [0-9.]+ > " + _N, "iso9283/verify_backlash_command", "threshold",
                      0.0),
                     ("verify remaining T", _BC + r"(?s:.*?)remaining\s+T = " + _N, "iso9283/verify_backlash_command",
                      "remaining_T", 0.02),
                     ("verify remaining threshold", _BC + r"(?s:.*?)remaining\s+T = [0-9.]+ <= " + _N,
                      "iso9283/verify_backlash_command", "remaining_threshold", 0.0),
                     ("verify backlash", _BC + r"(?s:.*?)`J2 backlash \+" + _N, "iso9283/verify_backlash_command",
                      "backlash_deg", 0.005),
                     ("verify backlash std", _BC + r"(?s:.*?)`J2 backlash \+[0-9.]+ ± " + _N,
                      "iso9283/verify_backlash_command", "backlash_std_deg", 0.02),
                     ("verify exit", _BC + r"(?s:.*?) deg`, exit " + _N, "iso9283/verify_backlash_command",
                      "exit_code", 0.0),
                     ("wear RP trend per day", r"so it grows by " + _N + " mm a day", "iso9283/wear_per_day",
                      "worn.RP.slope_mm_per_day", 0.0))]

# ---- docs/reliability.md ----
_REL = "docs/reliability.md"
_DR = "handeye/default_real/"
PAGE_FIGURES += [Figure(f"reliability:{k}", _REL, pat, prod, field, rel_tol=tol)
                 for k, pat, prod, field, tol in (
                     ("lm stop iterations", r"the rule above stops after " + _N, "reliability/lm_stop_linear",
                      "iterations", 0.0),
                     ("lm stop excess", r"the rule above stops after [0-9]+,\s+" + _N + " above it",
                      "reliability/lm_stop_linear", "excess", 0.05),
                     ("handeye angle charuco", r"ROS-Industrial sets " + _N + " and", _DR + "test_set_charuco",
                      "gate.angle_mismatch_deg", 0.02),
                     ("handeye angle 10x10", r"ROS-Industrial sets [0-9.]+ and " + _N + " deg", _DR + "test_set_10x10",
                      "gate.angle_mismatch_deg", 0.02),
                     ("camera charuco rms", r"ROS-Industrial ChArUco set " + _N + " px",
                      "handeye/camera_real/test_set_charuco", "rms_px", 0.0),
                     ("camera rendered rms", r"rendered images " + _N + r" px\) fails", "reliability/camera_gate",
                      "clean_rms_px", 0.1),
                     ("camera stretched rms", r"sideways\s+\(another camera, a resampling\): " + _N + " px, refused",
                      "reliability/camera_gate", "stretched_rms_px", 0.02),
                     ("touch-up tcp off", r"the RMS gate alone passed it, TCP " + _N + " mm off",
                      "reliability/touchup_one_pose_off", "tcp_error_mm", 0.0))]

# ---- docs/robots.md ----
_ROB = "docs/robots.md"
_RF = "robots/file_checks"
PAGE_FIGURES += [Figure(f"robots:{k}", _ROB, pat, prod, field, rel_tol=tol)
                 for k, pat, prod, field, tol in (
                     ("bx200l reach", r"largest wrist-centre reach of " + _N + " mm", _RF, "bx200l.reach_mm", 0.0),
                     ("ur10e zero x", r"At q = 0 the flange is at \(" + _N, _RF, "ur10e.zero.x", 0.0),
                     ("ur10e zero y", r"At q = 0 the flange is at \([−-]?[0-9.]+, " + _N, _RF, "ur10e.zero.y", 0.0),
                     ("ur10e zero z", r"At q = 0 the flange is at \([−-]?[0-9.]+, [−-]?[0-9.]+, " + _N, _RF,
                      "ur10e.zero.z", 0.0),
                     ("nao hands x", r"the hands are at \(" + _N, _RF, "nao.left_hand.x", 0.0),
                     ("nao hands y", r"the hands are at \([0-9.]+, \+-" + _N, _RF, "nao.left_hand.y", 0.0),
                     ("nao hands z", r"the hands are at \([0-9.]+, \+-[0-9.]+, " + _N, _RF, "nao.left_hand.z", 0.0),
                     ("nao camera x", r"and the top camera at \(" + _N, _RF, "nao.camera_top.x", 0.0),
                     ("nao camera z", r"and the top camera at \([0-9.]+, 0, " + _N, _RF, "nao.camera_top.z", 0.0),
                     ("boby nominal rms all poses", r"nominal DH plus a fitted base and 3 SMR points gives " + _N,
                      "robots/boby_nominal_all_poses", "rms", 0.0),
                     ("hilti flat rigid per station", r"A rigid fit per station on `flat\.yaml` gives " + _N,
                      "robots/hilti_flat_rigid", "rms", 0.0))]

# ---- docs/fleet.md ----
_MC = r"fleet:monte-carlo`: UR10(?s:.*?)"
PAGE_FIGURES += [Figure(f"fleet:monte-carlo {k}", "docs/fleet.md", _MC + pat, "fleet/monte_carlo", field, rel_tol=tol)
                 for k, pat, field, tol in (
                     ("median after", r"the Monte-Carlo median is\s+" + _N + " mm", "after.median", 0.0),
                     ("predicted", r"mm against " + _N + " mm predicted", "predicted", 0.0),
                     ("ratio", r"mm predicted, " + _N + "x the prediction", "ratio", 0.0),
                     ("unconverged", r"the prediction; " + _N + r" of the 200 solves", "unconverged", 0.0))]
PAGE_FIGURES += [Figure(f"fleet:pose-sets holdout {k}", "docs/fleet.md", r"which dominated it:\s+" + pat, "fleet/pose_sets",
                        f"holdout_rms_mm.{k}", rel_tol=0.0)
                 for k, pat in (("min", _N + "-"), ("max", r"[0-9.]+-" + _N + " mm over the 12 sets"))]

# ---- docs/thermal.md ----
_TH = "docs/thermal.md"
_ID = r"Measured: 8 deltas \(a1, a2(?s:.*?)"
_CP = r"Thermal drifts are small, so the first step leaves\s+~"
_OUT = r"\*\*What is outside the model, measured\*\*(?s:.*?)"
PAGE_FIGURES += [Figure(f"thermal:{k}", _TH, pat, prod, field, rel_tol=tol)
                 for k, pat, prod, field, tol in (
                     ("orthonormality", r"orthonormal to ~" + _N + r" \(`orthonormality_error`", "thermal_core/orthonormality",
                      "median", 0.5),
                     ("second-order remainder", r"\(Gauss–Newton\), removing the ~" + _N + " mm", "thermal_core/identification",
                      "linear.rms_after_mm", 0.5),
                     ("exact with 2 iterations", _ID + r"exact to " + _N + " with 2 iterations", "thermal_core/identification",
                      "exact2.max_error", 0.5),
                     ("linear max error", _ID + r"off by\s+at most " + _N, "thermal_core/identification", "linear.max_error",
                      0.1),
                     ("linear residual", _ID + r"\(mm or rad; residual " + _N + " mm", "thermal_core/identification",
                      "linear.rms_after_mm", 0.5),
                     ("noisy condition low", _ID + r"condition ≈ " + _N, "thermal_core/identification", "noisy.condition.min",
                      0.0),
                     ("noisy condition high", _ID + r"condition ≈ [0-9]+–" + _N, "thermal_core/identification",
                      "noisy.condition.max", 0.0),
                     ("noisy lengths low", _ID + r"RMS errors " + _N, "thermal_core/identification", "noisy.lengths_mm.min",
                      0.0),
                     ("noisy lengths high", _ID + r"RMS errors [0-9.]+–" + _N, "thermal_core/identification",
                      "noisy.lengths_mm.max", 0.0),
                     ("noisy angles low", _ID + r"for the lengths and\s+" + _N, "thermal_core/identification",
                      "noisy.angles_deg.min", 0.0),
                     ("noisy angles high", _ID + r"for the lengths and\s+[0-9.]+–" + _N, "thermal_core/identification",
                      "noisy.angles_deg.max", 0.0),
                     ("compensation one step median", _CP + _N + " mm \\(median", "thermal_core/compensation",
                      "one_step.median_mm", 0.5),
                     ("compensation one step max", _CP + r"[0-9e.−-]+ mm \(median; up to " + _N, "thermal_core/compensation",
                      "one_step.max_mm", 0.0),
                     ("compensation two steps median", _CP + r"(?s:.*?)and the second ~" + _N, "thermal_core/compensation",
                      "two_steps.median_mm", 0.5),
                     ("compensation two steps max", _CP + r"(?s:.*?)and the second ~[0-9e.−-]+ mm \(up to " + _N,
                      "thermal_core/compensation", "two_steps.max_mm", 0.1),
                     ("compensation drift", _CP + r"(?s:.*?)measured on 50 program points with " + _N + " mm drift",
                      "thermal_core/compensation", "drift_before_max_mm", 0.0),
                     ("compensation iterations", _CP + r"(?s:.*?)after ≤ " + _N + " iterations", "thermal_core/compensation",
                      "iterations_max", 0.0),
                     ("compensation iterations position only", _CP + r"(?s:.*?)iterations \(≤ " + _N + " for position only",
                      "thermal_core/compensation", "position_only.iterations_max", 0.0),
                     ("bending span", _OUT + r"span of the 24 free parameters to " + _N + " %",
                      "thermal_core/deformation_transfer", "bend.span.max", 0.05),
                     ("bending transfer", _OUT + r"carries over to the car body to ~" + _N + " %",
                      "thermal_core/deformation_transfer", "bend.transfer.max", 0.0),
                     ("sag in span", _OUT + r"the car body alone it is " + _N + " % a parameter change",
                      "thermal_core/deformation_transfer", "sag.in_span.min", 0.0),
                     ("sag transfer low", _OUT + r"poses leaves " + _N + "–", "thermal_core/deformation_transfer",
                      "sag.transfer.min", 0.0),
                     ("sag transfer high", _OUT + r"poses leaves [0-9]+–" + _N + " % of it", "thermal_core/deformation_transfer",
                      "sag.transfer.max", 0.0),
                     ("seed 9 second evaluation run", r"and scored [0-9.]+ % and\s+" + _N + " %", "thermal/realistic",
                      "seed.9.evaluation.screened.1", 0.0),
                     ("five selected low", r"α4 — are selected in " + _N + "–", "thermal/selection_ranges", "five.min", 0.005),
                     ("five selected high", r"α4 — are selected in [0-9]+–" + _N + " %", "thermal/selection_ranges",
                      "five.max", 0.0),
                     ("others selected high", r"almost equally well \(each [0-9]+–" + _N + " %", "thermal/selection_ranges",
                      "others.max", 0.0))]
_TG = r"With the true geometry \(a robot\s+file, as a geometric calibration gives\)(?s:.*?)"
PAGE_FIGURES += [Figure(f"thermal:calibrate-sensor true geometry {k}", _TH, _TG + pat, prod, field, rel_tol=0.02)
                 for k, pat, prod, field in (
                     ("realistic frame", r"give the frame within " + _N + " mm", "thermal_cli/realistic",
                      "sensor_true.at_point_mm"),
                     ("realistic rotation", r"at\s+the measurement volume, " + _N + "°", "thermal_cli/realistic",
                      "sensor_true.rotation_deg"),
                     ("realistic P_e", r"and `P_e` within " + _N + " mm on this realistic cell", "thermal_cli/realistic",
                      "sensor_true.P_e_mm"),
                     ("ideal frame", r"preset's cell \(the test's\) " + _N + " mm", "thermal_cli/ideal",
                      "sensor_true.at_point_mm"),
                     ("ideal rotation", r"preset's cell \(the test's\) [0-9.]+ mm, " + _N + "°", "thermal_cli/ideal",
                      "sensor_true.rotation_deg"),
                     ("ideal P_e", r"preset's cell \(the test's\) [0-9.]+ mm, [0-9.]+° and " + _N + " mm", "thermal_cli/ideal",
                      "sensor_true.P_e_mm"))]

# ---- docs/datasets.md ----
_OA = r"fitted to the target origin\s+alone it gives "
PAGE_FIGURES += [Figure(f"datasets:positioner reference origin alone {k}", "docs/datasets.md", _OA + pat,
                        "datasets/positioner_reference", field, rel_tol=tol)
                 for k, pat, field, tol in (
                     ("angle", _N + "°", "origin.angle_deg", 1e-6),
                     ("common normal", r"[0-9.]+° / " + _N + " mm", "origin.common_normal_mm", 0.002),
                     ("angle sigma", r"[0-9.]+° / [0-9.]+ mm \(σ " + _N, "origin.angle_sigma", 0.02),
                     ("common normal sigma", r"[0-9.]+° / [0-9.]+ mm \(σ [0-9.]+° / " + _N, "origin.common_normal_sigma",
                      0.02))]

# ---- docs/handeye.md ----
_SB = r"images the classic path is the more accurate: "
PAGE_FIGURES += [Figure(f"handeye:classic vs SB {k}", "docs/handeye.md", _SB + pat, "handeye/classic_vs_sb", field,
                        rel_tol=0.02)
                 for k, pat, field in (("classic", _N + " against", "classic"),
                                       ("SB low", r"[0-9.]+ against " + _N + "-", "sb.min"),
                                       ("SB high", r"[0-9.]+ against [0-9.]+-" + _N + " px", "sb.max"))]

# ---- docs/robot-files.md ----
_PB = r"Measured \(`tests/test_parallel_beta\.py`(?s:.*?)"
PAGE_FIGURES += [Figure(f"robot-files:parallel beta {k}", "docs/robot-files.md", _PB + pat, "robot_files/parallel_beta",
                        field, rel_tol=0.02)
                 for k, pat, field in (("holdout", r"held-out RMS " + _N + " mm with or without", "plain.holdout_rms_mm"),
                                       ("holdout declared", r"held-out RMS " + _N + " mm with or without",
                                        "declared.holdout_rms_mm"),
                                       ("holdout beta3 held", r"the held-out error is " + _N + " mm",
                                        "no_beta.holdout_rms_mm"))]

# ---- docs/self-calibration-simulator.md ----
_SCS = "docs/self-calibration-simulator.md"
_BOW = r"\| 0 \(off\); 0\.4 mm moves NAO corners by "
PAGE_FIGURES += [Figure(f"self-calibration-simulator:bent board {k}", _SCS, _BOW + pat, "self_calibration_sim/bent_board",
                        field, rel_tol=0.0)
                 for k, pat, field in (("low", _N + "-", "gap_px.min"), ("high", r"[0-9.]+-" + _N + " px", "gap_px.max"))]
for _row, (_robot, _seed) in ((r"`nao_h25`, both hands, seed 1", ("nao_h25", 1)),
                              (r"`nao_h25`, both hands, seed 7", ("nao_h25", 7)),
                              (r"`kuka_kr150_r3100`, world board, seed 3", ("kuka_kr150_r3100", 3))):
    PAGE_FIGURES += [Figure(f"self-calibration-simulator:rendered {_robot} seed {_seed} {f}", _SCS, _cell(_row, c, k),
                            f"self_calibration_sim/{_robot}/{_seed}", f, rel_tol=0.0)
                     for c, k, f in ((0, 0, "full.detected"), (0, 1, "full.total"), (1, 0, "partial.rejected"),
                                     (1, 1, "partial.total"), (2, 0, "rms_px"), (2, 1, "max_px"))]
_RR = r"The rendered images add their own corner error \(RMS "
PAGE_FIGURES += [Figure(f"self-calibration-simulator:rendered rms {k}", _SCS, _RR + pat, "self_calibration_sim/rendered_range",
                        field, rel_tol=0.0)
                 for k, pat, field in (("low", _N + "-", "rms_px.min"), ("high", r"[0-9.]+-" + _N + " px", "rms_px.max"))]

# ---- docs/self-calibration.md ----
_NR = r"self-calibration:nao rendered`\): "
PAGE_FIGURES += [Figure(f"self-calibration:nao rendered {k}", "docs/self-calibration.md", _NR + pat,
                        "self_calibration/nao_rendered", field, rel_tol=tol)
                 for k, pat, field, tol in (
                     ("used", _N + " of the", "n_used", 0.0),
                     ("images", r"[0-9]+ of the " + _N + " images", "n_images", 0.0),
                     ("wrong hand", r"(?s:.*?)to the right hand \(" + _N + " wrong", "n_misassigned", 0.0),
                     ("identifiable", r"(?s:.*?)the " + _N + r" identifiable offsets", "n_identifiable", 0.0),
                     ("max |z|", r"(?s:.*?)identifiable offsets within " + _N, "max_abs_z", 0.02),
                     ("max error", r"(?s:.*?)\(errors <= " + _N + "°", "max_error_deg", 0.02),
                     ("sigma low", r"(?s:.*?)sigmas " + _N + "-", "sigma_deg.min", 0.02),
                     ("sigma high", r"(?s:.*?)sigmas [0-9.]+-" + _N + "°", "sigma_deg.max", 0.02),
                     ("rms", r"(?s:.*?)back-projection RMS " + _N + " px", "rms_px", 0.01))]
_RN = r"Measured by `pytest tests/test_self_calibration_pipeline\.py` \(DLR Justin head camera(?s:.*?)"
PAGE_FIGURES += [Figure(f"self-calibration:justin reading noise {k}", "docs/self-calibration.md", _RN + pat,
                        "self_calibration/justin_reading_noise", field, rel_tol=tol)
                 for k, pat, field, tol in (
                     ("exact variance factor", r"taken as exact, variance factor " + _N, "exact.variance_factor", 0.02),
                     ("exact offsets sigma", r"variance factor [0-9.]+ and offsets " + _N, "exact.max_abs_z", 0.03))]
