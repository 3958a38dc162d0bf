"""Named slots of the arrays and tuples the simulator's kernels share, and their codes.

Each group is one table of ``(name, meaning)`` rows; the index constants below it are
unpacked from ``range`` in the table's order and checked against it at import (so a row
moved or added in one place and not the other fails at once). They are plain module-level
ints: numba reads them as compile-time constants, so ``P[P_DELTA]`` costs what ``P[3]`` did.

- ``P``: the parameter vector (float64, built by
  :func:`vibroimpact.impact.parameters.parameters`; from a model,
  :func:`vibroimpact.impact.simulate.model_parameters`);
- ``c``: the segment tuple returned by :func:`vibroimpact.impact.motion.segment`;
- ``state``: the kernel's state at a sample point (float64, kept by the driver between calls);
- ``cnt``: the event counters (int64);
- ``ftot``: the float record (float64): the time in contact, and what a step that gave up
  saw (the driver's error message).
"""

P_FIELDS = (
    ("zeta", "damping ratio"),
    ("omega", "damped frequency sqrt(1 - zeta^2)"),
    ("eps", "restitution coefficient (at vanishing impact speed)"),
    ("delta", "wall position"),
    ("dt", "force sample step h"),
    ("A", "harmonic amplitude"),
    ("beta", "harmonic frequency"),
    ("Aq", "amplitude A q of the harmonic particular solution"),
    ("phi", "its phase lag"),
    ("cos_phi", "cos(phi)"),
    ("sin_phi", "sin(phi)"),
    ("bh_hi", "beta h in double-double, high part"),
    ("bh_lo", "beta h in double-double, low part"),
    ("m11", "free-response propagator over h, row 1 column 1"),
    ("m12", "free-response propagator over h, row 1 column 2"),
    ("m21", "free-response propagator over h, row 2 column 1"),
    ("m22", "free-response propagator over h, row 2 column 2"),
    ("inv_dt", "1 / h"),
    ("inv_omega", "1 / omega"),
    ("cos_bh", "cos(beta h): one rotation of the harmonic phase"),
    ("sin_bh", "sin(beta h)"),
    ("law_a", "the impact law's 1 / speed_scale: eps(u) = eps / (1 + a |u|); 0: Newton's"),
)
(P_ZETA, P_OMEGA, P_EPS, P_DELTA, P_DT, P_A, P_BETA, P_AQ, P_PHI, P_COS_PHI, P_SIN_PHI,
 P_BH_HI, P_BH_LO, P_M11, P_M12, P_M21, P_M22, P_INV_DT, P_INV_OMEGA, P_COS_BH,
 P_SIN_BH, P_LAW_A) = range(len(P_FIELDS))
N_PARAMS = len(P_FIELDS)

C_FIELDS = (
    ("xd", "x0 - delta at the segment's start"),
    ("v0", "x' at the start"),
    ("b", "slope of the random force r over the step"),
    ("sp", "sin(psi0), psi0 = beta tau0 - phi the harmonic solution's phase"),
    ("cp", "cos(psi0)"),
    ("y0", "free response y = x - p_lin - p_h at the start"),
    ("yv0", "its velocity"),
    ("c2", "coefficient of exp(-zeta s) sin(omega s) in y"),
    ("d2", "minus the coefficient of exp(-zeta s) sin(omega s) in y'"),
    ("R", "amplitude of y (a bound on every derivative of y)"),
    ("g2", "x'' at the start"),
    ("g3", "x''' at the start"),
    ("f0", "F = f - delta at the start: the push into the wall at x = delta"),
    ("df0", "dF / dtau at the start"),
    ("sin_t", "sin of the forcing phase beta tau0"),
    ("cos_t", "cos of the forcing phase"),
    ("f_lin", "r0 + b s: the random force at the start"),
)
(C_XD, C_V0, C_B, C_SP, C_CP, C_Y0, C_YV0, C_C2, C_D2, C_R, C_G2, C_G3, C_F0, C_DF0,
 C_SIN_T, C_COS_T, C_F_LIN) = range(len(C_FIELDS))

S_FIELDS = (
    ("w", "x - p_h: the displacement less the harmonic particular solution"),
    ("wv", "x' - p_h'"),
    ("mode", "FREE, STUCK or WALL"),
    ("sin_psi", "sin(psi), psi = beta k h - phi"),
    ("cos_psi", "cos(psi)"),
)
S_W, S_WV, S_MODE, S_SIN_PSI, S_COS_PSI = range(len(S_FIELDS))
N_STATE = len(S_FIELDS)

CNT_FIELDS = (
    ("impacts", "impacts written"),
    ("stick_events", "sticking onsets and releases written"),
    ("chatter", "chatter sequences closed at their accumulation point"),
)
CNT_IMPACTS, CNT_STICK_EVENTS, CNT_CHATTER = range(len(CNT_FIELDS))
N_COUNTERS = len(CNT_FIELDS)

# ftot stays one array rather than a contact-time argument plus a diagnostics argument:
# every argument and branch added to run_steps slows its hot loop (benchmarks/ab_no_impact.py)
FT_FIELDS = (
    ("contact_time", "time resting on the wall"),
    ("offset", "gave up: the offset reached in the step"),
    ("gap", "gave up: x - delta there"),
    ("v", "gave up: x' there"),
    ("mode", "gave up: the mode there"),
    ("impacts", "gave up: impacts written in the step"),
    ("stick_events", "gave up: sticking events written in the step"),
)
(FT_CONTACT_TIME, FT_OFFSET, FT_GAP, FT_V, FT_MODE, FT_IMPACTS,
 FT_STICK_EVENTS) = range(len(FT_FIELDS))
N_FTOT = len(FT_FIELDS)
#: The slots of a step that gave up (``ftot[FT_DIAGNOSTICS]``), in FT_FIELDS order.
FT_DIAGNOSTICS = slice(FT_OFFSET, N_FTOT)

# status codes returned by run_steps and slow_step
OK = 0
BUFFER_FULL = 1
TOO_MANY_EVENTS = 2
BAD_NOISE = 3

# modes
FREE = 0
STUCK = 1
#: Free, and exactly on the wall (x = delta, x' <= 0) at the step's start: an impact, a touch
#: or a release fell on the end of the previous step. Kept apart from FREE so that the state
#: is handed on exactly, not through the round-off of ``w = x - p_h``.
WALL = 2
#: The same two modes at the second wall of a clearance (x = delta - gap, below the mass).
STUCK_LO = 3
WALL_LO = 4

# the two walls: the parameter vector ``P`` holds N_PARAMS slots per wall, the upper wall's
# (the paper's, at x = delta) first; the lower wall's half is that wall in the mirrored frame
# x -> -x (vibroimpact.impact.parameters.parameters), so every search serves both walls.
# In the event buffers the wall is the sign of ``imp_u`` (the lab-frame velocity x' at the
# impact: > 0 at the upper wall, < 0 at the lower) and the kind of a sticking event:
STICK_OFF = 0.0      # release from the upper wall
STICK_ON = 1.0       # sticking onset at the upper wall
STICK_LO = 2.0       # added to the kind at the lower wall (2: release, 3: onset)

# search results of first_contact
NO_ROOT = 0
ROOT = 1
TOUCH = 2   # reaches the wall with zero velocity (grazing within round-off)
PRESSED = 3  # at the wall, at rest, pushed into it: sticks


def _check(prefix, fields):
    names = [prefix + name.upper() for name, _ in fields]
    found = [globals().get(n) for n in names]
    if found != list(range(len(fields))):
        raise ImportError(f"{__name__}: the {prefix}* constants do not follow their table: "
                          f"{dict(zip(names, found))}")


for _prefix, _fields in (("P_", P_FIELDS), ("C_", C_FIELDS), ("S_", S_FIELDS),
                         ("CNT_", CNT_FIELDS), ("FT_", FT_FIELDS)):
    _check(_prefix, _fields)
