"""Every numerical threshold of the orbit kernels, in one block, each with its reason.

Plain module-level numbers: numba reads them as compile-time constants when a kernel compiles,
so a named value costs what the literal did and gives the same bits. The kernels' cache is
stamped with this file (:mod:`vibroimpact.orbits._jit`): a value changed here takes effect.
"""

#: Reason codes of the map (``orbits.api.Reason``): why a point has no stable motion of a type.
REASON_STABLE, REASON_NO_SOLUTION, REASON_INADMISSIBLE, REASON_UNSTABLE = 0, 1, 2, 3

# --- Newton, the uncertainty of a solution, one orbit once -----------------------------------
NEWTON_MAXIT = 30            # iterations at most: a start not converged by then is dropped
NEWTON_GIVE_UP_IT = 10       # a start still this far off after this many steps is abandoned
NEWTON_GIVE_UP_RTOL = 1e-4   # "this far off": residual over the scale (no quadratic basin yet)
NEWTON_RTOL = 1e-12          # residual tolerance, relative to the problem's displacement scale
# Float64 evaluation noise of the residual at an exact solution, relative to the scale: measured
# <= 2.5e-15 (median 2.4e-16) at 150 mpmath-polished orbits of (1/1), (2/1), (2/2), (1/2); 4x
# that. Below it a Newton step is driven by round-off alone (near a fold or a period doubling,
# where |mu - 1| is tiny, such a step moves the orbit by noise/|mu - 1|), so Newton stops there.
RESIDUAL_NOISE_RTOL = 1e-14
# Once the residual is below NEWTON_RTOL, Newton goes on while a full step at least halves the
# residual (quadratic convergence does far better) and stops when it does not: the step is then
# dominated by round-off and would only move the solution along a near-null direction.
NEWTON_POLISH_DECREASE = 0.5
NEWTON_STEP_RTOL = 1e-14     # converged on the step: |dy_i| <= this * (1 + |y_i|) (a few ulps)
SAME_ORBIT_RTOL = 1e-7       # two solutions closer than this (phase/T_f, velocity/scale) are one
# Uncertainty of a solution (added to SAME_ORBIT_RTOL in the dedupe and repeated-orbit tests):
# UNCERTAINTY_SAFETY * |J^-1| (residual + noise), per component, in the units of
# SAME_ORBIT_RTOL. The factor covers the first-order bound's neglect of curvature (a Newton
# point stopped in the flat, noise-level region between close roots: then the bound is >= its
# distance to either root for any factor >= 1). At the doubled (1/1) motion 1e-10 in delta from
# a period doubling the bound is 6e-5 .. 3e-3 (it takes the noise at its ceiling), while Newton
# copies of that motion landed ~5e-7 off it (relative): the cap decides there. It is 100 x
# SAME_ORBIT_RTOL, above those copies' errors and 10 x below the 1e-4 at which the independent
# check pairs orbits, so a (near) singular J never merges orbits that are clearly apart.
UNCERTAINTY_SAFETY = 4.0
UNCERTAINTY_CAP = 1e-5
ADMISSIBLE_TOL = 1e-12       # margin >= -tol counts as admissible (grazing is the edge, included)
MAX_SOLUTIONS = 64           # capacity per (m/n) type and parameter point
# Interval-scan steps, in radians of the fastest of beta and wd (m = 2: 1-D scan, m = 3: per
# axis of a 2-D scan); the map also follows branches, so it affords a coarser scan.
SCAN_STEP_M2 = 0.02
SCAN_STEP_M3 = 0.12
EDGE_LEVELS = 6              # m = 2 scan: extra nodes at 10^-6 .. 10^-1 steps from both ends
MAP_SCAN_STEP_M2 = SCAN_STEP_M2   # m = 2 scans are cheap: the map scans every point
MAP_SCAN_STEP_M3 = 0.25
MAP_SCAN_EVERY = 4           # map: global scan at every 4th delta; branches followed in between
# m = 2 scan, near-tangencies: a local extremum of a circle factor (no sign change around it)
# is refined when the parabola through its three nodes comes within TANGENCY_MARGIN * a2 H^2
# of zero (a2: the parabola's curvature, H: the wider cell). The parabola predicts the
# extremum to ~H g'''/g'' (~2% at 0.02 rad nodes) of a2 H^2, so a pair of roots hidden in
# the cells (the two orbits next to a fold, ~sqrt(distance) apart) is never skipped.
TANGENCY_MARGIN = 1.0
# The refinement (Brent's minimization) stops at this fraction of the two cells: a hidden pair
# ~1e-7 apart (a fold ~1e-14 away in delta) still shows a negative value at that resolution.
TANGENCY_XTOL = 1e-9
ROOT_MAXIT = 100             # Brent root/minimum iterations (bisection bound ~60 for float64)
FLIGHT_PHASE_STEP = 0.5      # admissibility: initial bracketing step (radians), refined by bounds
FLIGHT_MIN_STEP = 1e-9       # admissibility: smallest bracket before giving up refinement

# --- inner iterations -----------------------------------------------------------------------
#: Keeps a scale positive when it is zero (Brent's tolerance at b = 0).
TINY = 1e-300
#: Halvings of a Newton step tried before the step is rejected (the last tries 1/128 of it).
NEWTON_LINE_SEARCH = 8
#: Brent's root tolerance ``2 eps |b|`` with eps written 2.2e-16 (a few ulps of ``z_1``; the
#: value of the classic implementations, kept as it is).
BRENT_ROOT_REL = 4.4e-16
#: ``(3 - sqrt 5) / 2``: the golden-section fraction of Brent's minimization.
GOLDEN_SECTION = 0.3819660112501051
#: Admissibility: iterations of the safeguarded Newton on the velocity's zero in a bracket
#: proved to hold one (bisection alone reaches round-off in ~60), and its stop: a step or a
#: bracket below 1e-15 of the flight (a few ulps).
FLIGHT_MAX_MAXIT = 60
FLIGHT_MAX_XTOL = 1e-15
#: Admissibility: the initial brackets of a flight are at least this many.
FLIGHT_MIN_BRACKETS = 4
#: Rows of the bisection stack of ``flight_max`` (its scratch ``stack``): a bisection adds one
#: row per level, and ~30 levels bring a bracket below FLIGHT_MIN_STEP, far from 64.
FLIGHT_STACK = 64
#: Fewest scan nodes along ``z_1`` (m = 2) and per axis of the triangle (m = 3), whatever
#: the step: the circle condition has at least a few oscillations over a period.
M2_MIN_NODES = 16
M3_MIN_NODES = 12
#: m = 3: the scan's nodes sit this fraction of a step inside the interval triangle, off its
#: edges, where a zero-length flight makes the linear system singular.
M3_NODE_OFFSET = 1.0 / 3.0
#: m = 3: a cell where the circle function keeps its sign is still tried when it comes this
#: close to zero (it is normalized to at most 1) and det K changes sign: zero curves that
#: touch between nodes.
M3_CIRCLE_NEAR = 0.1
#: m = 3: the common zero of the two bilinear interpolants of a cell: Newton iterations, the
#: step below which it has converged (cell units), how far out it may wander before it is
#: abandoned (from the cell's centre), and the accepted region: the cell widened by a quarter
#: on each side (a zero just outside a cell is also tried from its neighbour, but the two
#: interpolants differ).
BILINEAR_MAXIT = 12
BILINEAR_XTOL = 1e-6
BILINEAR_DIVERGED = 2.0
BILINEAR_ACCEPT = 0.75

# --- stable-domain boundaries (boundaries.py, boundaries_kernels.py) --------------------------
#: Central-difference step of the test functions' and the parameters' derivatives, relative to
#: 1 + |x|: ~ the cube root of the float64 epsilon, balancing truncation (h^2 ~ 4e-11) and
#: round-off (1e-16 / h ~ 2e-11), so the augmented Jacobian is good to ~1e-10 relative and
#: Newton gains ~10 digits per step (the equations themselves are evaluated exactly).
BOUNDARY_FD_REL = 6e-6
#: Newton on the augmented system: iterations at most (it converges in 3-5 from a predictor).
BOUNDARY_NEWTON_MAXIT = 30
#: Converged when the last Newton correction of every unknown is below this times 1 + |x|:
#: the correction estimates the distance to the exact root (it is J^-1 F), so delta is exact to
#: ~1e-12 (1 + |delta|), well inside the 1e-9 asked of the curves.
BOUNDARY_STEP_RTOL = 1e-12
#: Grazing curves: the grid (radians of the fastest of beta and wd) on which a flight's highest
#: maximum is located before Newton converges it (``flight_peak``); x oscillates with periods
#: >= 2 pi in those units, so 0.05 rad puts >= 60 nodes on every oscillation.
BOUNDARY_PEAK_STEP = 0.05
