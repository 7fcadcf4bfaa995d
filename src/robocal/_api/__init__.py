"""robocal's public facade (re-exported lazily by :mod:`robocal`; this path is private).

One small module per entry: :mod:`.loading` (robots, measurement files), :mod:`.calibration`
(geometric calibration in memory), :mod:`.correction` (corrected joint targets), :mod:`.handeye`
(hand-eye transform), :mod:`.tool` (tool centre point).
"""
