"""Every numerical threshold of the simulator's kernels, in one block, each with its reason.

Plain module-level numbers: numba reads them as compile-time constants when a kernel compiles
(``X * EPS64`` written with a name costs what the literal did, and gives the same bits). A
value changed here takes effect in kernels compiled afterwards (the package's numba cache is
stamped with this file, :mod:`vibroimpact.impact._jit`).

Three kinds: round-off multiples (``*_ULPS`` and ``*_REL``: how many units of the float64
round-off ``EPS64`` of the quantity's own scale a comparison allows, and why that many),
event tolerances (what the motion may neglect; tests/test_collisions.py scales them by 1e3
both ways and checks that no collision statistic moves), and iteration limits.
"""

#: Unit round-off of float64 (2^-52): ``x + EPS64 |x|`` is the next float after ``x > 0``
#: up to a factor 2 (one ulp of ``x`` lies in ``[EPS64 |x| / 2, EPS64 |x|]``).
EPS64 = 2.220446049250313e-16
#: Keeps a sum of absolute values positive when every term is zero (a scale of 0 would make
#: a strict ``<`` test against it fail, and a tolerance of 0 demand exact equality); far
#: below every physical scale (the smallest normal float is 2.2e-308).
TINY = 1e-300

# --- round-off multiples --------------------------------------------------------------------
#: Relative inflation of every derivative bound (``M2, M3, M4`` and the force's ``A beta^2``),
#: covering round-off in the bound itself: a bound is a sum of a few products, each exact to
#: a few ulps; 1e-12 is ~5000 ulps, so the bound stays a bound.
BOUND_SAFETY = 1.0 + 1e-12
#: ``2 EPS64``: a step shorter than this relative to the abscissa no longer moves it (one ulp
#: is at most ``EPS64 |s|``; twice that allows the rounding of the step's own end): root
#: polishing, the release search and the contact search stop there.
STALL_REL = 2.0 * EPS64
#: ``4 EPS64``: a polished root still on the negative side with the bracket's end this close
#: (the stall test's two ulps, for each of the two ends) has its sign change between here
#: and the end: the end is taken as the root, so that the impact is never left behind.
BRACKET_END_REL = 4.0 * EPS64
#: ``2 EPS64``: the last Halley step is taken without a new evaluation when the velocity's
#: Taylor remainder ``M3 d^2 / 2`` is below one ulp of ``v`` (``M3 d^2 <= 2 EPS64 v``).
JERK_REMAINDER_REL = 2.0 * EPS64
#: ``8 EPS64``: a gap ``x - delta`` above minus this (on the scale of ``|x0 - delta|`` plus
#: the distance the motion covers) counts as reaching the wall in the contact search: ``g``
#: from ``seg_eval`` is a sum of a few rounded terms of that scale, so its own round-off is a
#: few ulps of it; 8 leaves a margin over that estimate.
GAP_ULPS = 8.0
#: ``8 EPS64``: a push ``F = f - delta`` smaller than this (on the scale of ``|r|``,
#: ``|delta|``, ``A`` and ``|b| h``) has no sign: ``F`` is a sum of about four rounded terms of
#: that scale. The one tolerance of every stay-or-leave decision (``force_tol``).
FORCE_ULPS = 8.0
#: ``16 EPS64``: a separation from the wall below this (on the scale of ``|delta|``, ``|r|``,
#: ``A q`` and the free response's amplitude ``R``) is not resolvable (``tolg_wall``): ``x``
#: is rebuilt from terms of that size, so a smaller gap is round-off. Twice GAP_ULPS: the
#: separation compared with it is itself a bound, a sum of bounded terms.
WALL_ULPS = 16.0
#: ``64 EPS64``: an arrival slower than this (on the scale of every velocity term of the
#: segment, ``vscale``) is a touch, not an impact: the velocity at a root is a sum of terms of
#: that scale evaluated at a rounded root, so a few ulps of it have no sign; 64 is a wide
#: margin over that. No collision statistic depends on it (tests/test_collisions.py).
TOUCH_ULPS = 64.0
#: Margin of the fast path's exclusion test (``x_max + bound + margin < delta``), relative to
#: ``A q``: the rotated harmonic phase ``(sin psi, cos psi)`` drifts by up to ~1e-13 between
#: two resynchronisations (RESYNC_EVERY rotations, each exact to ~1 ulp), so ``A q sin psi``
#: is off by ~1e-13 ``A q``; 1e-11 leaves a factor 100. Plus TINY: without a harmonic force
#: there is nothing to cover and the margin is only there to be positive.
EXCLUSION_MARGIN_REL = 1e-11
#: Relative margin of the stay-on-the-wall test of a whole step in run_steps' fast path (on
#: the scale of the force), far above the round-off of the rotated harmonic phase (~1e-13
#: after RESYNC_EVERY steps); a step closer to a release goes through release_time.
STICK_MARGIN = 1e-9

# --- event tolerances -----------------------------------------------------------------------
#: Bound (in time) on the error of a chatter sequence's accumulation point, summed in closed
#: form (``chatter_tail``, a proved bracket): the sticking onset, and so the time on the
#: wall, is exact to it; nothing else depends on it (the release is the push's own root, and
#: the rebounds left unresolved, slower than RESOLVED_REBOUND, never change the collisions).
CHATTER_TIME_TOL = 1e-7
#: Where chatter_tail cannot bracket the tail inside the step (a tail across a sample point,
#: eps near 1), it is summed once the first-order estimate of its neglected terms,
#: ``T (2 zeta w + |F'| T) / F`` with ``T = 2 w / (F (1 - eps))``, is below this.
CHATTER_ESTIMATE_TOL = 1e-12
#: A chatter tail is summed only once its rebounds leave the wall slower than this (so that
#: every later approach, at most twice as fast, is below 1e-4): every faster rebound is
#: resolved, so counts of rebounds above a floor >= 1e-4 (the statistics' ``rebound_floor``)
#: are exact whatever CHATTER_TIME_TOL, and every impact faster than 1e-4 is in the record.
RESOLVED_REBOUND = 5e-5
#: Elastic (eps = 1) micro-bounces shorter than this are taken as resting contact: with eps = 1
#: a pressed mass loses bounce energy only to damping, so bounces shrink like 1/k and never
#: accumulate; a flight of 1e-6 rises ~1e-13 F above the wall.
ELASTIC_MICRO_FLIGHT = 1e-6
#: After MANY_EVENTS events in one step (eps very close to 1: chatter of ~1e5 impacts spread
#: over many steps; eps = 1 pressed on the wall with long steps), rebounds lower than
#: MICRO_HEIGHT * (1 + |delta|), or with flights too short for the rest of the step to hold
#: fewer than STEP_HEADROOM / MICRO_FLIGHTS_PER_HEADROOM more of them, are resting contact.
MANY_EVENTS = 4096
MICRO_HEIGHT = 1e-12
MICRO_FLIGHTS_PER_HEADROOM = 16.0
#: A Halley step this short is the last one: the next error, ~ d^3 (cubic convergence), is
#: below 1e-18, under the round-off of any offset in a step.
HALLEY_LAST_STEP = 1e-6
#: Where the push ``f - delta`` only touches zero (a tangency: the safe step vanishes) the
#: release search moves on by this fraction of the step: no sign change is skipped, since
#: the push is not negative there.
TANGENCY_STEP_REL = 1e-12
#: ``safe_step``'s fixed-point iteration stops once a new window is within 1 % of the last:
#: another iteration would lengthen the step by under 1 %, not worth its square root.
SAFE_STEP_CONVERGED = 0.99
#: ``chatter_tail``'s first window: this many times the constant-push estimate of the tail,
#: ``2 w / (F (1 - eps))``; a window too short is widened to CHATTER_WINDOW_GROWTH times the
#: bracket's upper end and tried again.
CHATTER_WINDOW = 1.5
CHATTER_WINDOW_GROWTH = 1.01

# --- iteration limits and capacities --------------------------------------------------------
#: Resynchronise the rotated harmonic phase used by the fast exclusion test every so many steps.
RESYNC_EVERY = 1024
#: Maximum number of root-search iterations in one segment (never reached in practice: the
#: search converges quadratically; a near-grazing approach takes ~30).
MAX_SEARCH = 400
#: Iterations of a bracketed root polish (Halley or Newton kept inside a bracket by bisection):
#: bisection alone halves the bracket to round-off in ~60.
POLISH_MAXIT = 100
#: Newton iterations on the cubic Hermite interpolant (a start, not a root: 4 are plenty).
HERMITE_MAXIT = 4
#: Fixed-point iterations of ``safe_step`` (it converges to 1 % in 2-3).
SAFE_STEP_MAXIT = 6
#: Windows ``chatter_tail`` tries before giving up for this step.
CHATTER_MAXIT = 4
#: Impacts and sticking events one step may write; the driver flushes buffers before a step
#: when less room than this is left.
STEP_HEADROOM = 1 << 16
