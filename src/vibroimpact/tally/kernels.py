"""The kernels of :mod:`vibroimpact.tally`: the collision grouping and the (m/n) labelling of a
record in one pass each, as numba loops.

Each kernel is the loop form of a numpy reference in :mod:`vibroimpact.stats` (the statement
of the rule, kept there and tested against this): ``group`` of
``stats.collisions.group_collisions`` followed by ``Collisions.after``, ``label`` of
``stats.motions._classify`` with the impact-stick refinement and the covered time of each
class up to given intervals (the cumulative sums of ``stats.motions._batch_stderr``). Every
value they return is an integer, a flag, a copy, or a float formed by the same operations in
the same order as the reference (elementwise products and differences, and sums taken
sequentially as ``numpy.cumsum`` takes them): the results are the reference's to the bit, not
to a tolerance. Sums that numpy takes pairwise (``ndarray.sum``) are left to numpy by the
callers.

They use no kernel or constant of another module, so their numba cache is stamped with this
file alone.
"""
import numpy as np
from numba import njit

from vibroimpact._kernel_cache import kernel_decorator

kernel = kernel_decorator(njit, __file__, ("kernels.py",), error_model="numpy")

#: ``rule`` codes of `group`, in the order of ``stats.RULES``
PHYSICAL, IMPACTS, REBOUNDS = 0, 1, 2


@kernel
def _ends(t, start):
    """``ends[i]``: a sticking phase begins in ``[t_i, t_{i+1})`` (``t_n = inf``); ``t`` and
    ``start`` increasing. Each phase marks the last impact at or before it (the merge of
    searchsorted ``side='left'`` run from the phases' side: one unpredictable branch per
    phase, not one per impact)."""
    n, m = t.size, start.size
    ends = np.zeros(n, np.bool_)
    i = -1
    for p in range(m):
        s = start[p]
        while i + 1 < n and t[i + 1] <= s:
            i += 1
        if i >= 0:
            ends[i] = True
    return ends


@kernel
def _chatter_firsts(cont, ends, first):
    """``first[j + 1] = False`` where impact ``j + 1`` joins the collision of ``j``
    (``stats.collisions._chatter_joins``: ``j`` on a run of links ``cont`` that ends in
    sticking at or after ``j``, and ``j`` itself does not end)."""
    n = ends.size
    next_end, next_break = n, n
    for j in range(n - 1, -1, -1):
        if ends[j]:
            next_end = j
        if not ends[j] and not cont[j]:
            next_break = j
        if j < n - 1 and next_end < n and next_break > next_end and not ends[j]:
            first[j + 1] = False


@kernel
def _at_firsts(first, t, step, offset, u, wall):
    """The time, step, offset, velocity and wall of the impacts ``first`` (the collisions'
    first impacts), gathered in one loop."""
    k = first.size
    time_first = np.empty(k)
    step_first = np.empty(k, np.int64)
    offset_first = np.empty(k)
    u_first = np.empty(k)
    wall_first = np.empty(k, np.int8)
    for c in range(k):
        a = first[c]
        time_first[c], step_first[c], offset_first[c] = t[a], step[a], offset[a]
        u_first[c], wall_first[c] = u[a], wall[a]
    return time_first, step_first, offset_first, u_first, wall_first


@kernel
def _first_mask(step, offset, u, t, ends, counted, dt, pressed, rule, wall):
    """``first_mask[i]``: impact ``i`` starts a collision under ``rule`` (``t`` the impacts'
    instants, ``ends`` `_ends`, ``counted`` the rebounds that reach the floor)."""
    n = step.size
    first_mask = np.ones(n, np.bool_)
    if rule == PHYSICAL:
        cont = np.zeros(n, np.bool_)
        for j in range(n - 1):
            cont[j] = not ends[j] and pressed[j]
        _chatter_firsts(cont, ends, first_mask)
    elif rule == REBOUNDS:
        for i in range(n):
            first_mask[i] = counted[i]
    else:
        # the impacts-only rule: shrinking rebounds and flights that end in sticking
        cont = np.zeros(n, np.bool_)
        for j in range(n - 1):
            if ends[j] or not u[j + 1] < u[j]:
                continue
            shrinks = True
            if j < n - 2:
                z0 = float(step[j + 1] - step[j]) * dt + (offset[j + 1] - offset[j])
                z1 = float(step[j + 2] - step[j + 1]) * dt + (offset[j + 2] - offset[j + 1])
                shrinks = z0 > z1
            cont[j] = ends[j + 1] or shrinks
        _chatter_firsts(cont, ends, first_mask)
    for i in range(1, n):
        if wall[i] != wall[i - 1]:
            first_mask[i] = True
    return first_mask


@kernel
def group(step, offset, u, start, end, dt, eps, floor, pressed, rule, wall, t0):
    """The collisions of a record at or after ``t0`` (``group_collisions(...).after(t0)``).

    ``eps`` holds the restitution of each impact's wall; ``pressed`` the hops (physical rule
    only, else unread); ``wall`` the wall of each impact (int8). Returns the fields of the
    kept collisions, ``first, impact_collision, rebounds, stuck, stick_time, duration`` and
    ``step, offset, time, velocity, wall`` at ``first``), after the number of rebounds that
    reach ``floor`` (rule "rebounds": none, no collision): ``(n_counted, first,
    impact_collision, step, offset, time, velocity, rebounds, stuck, stick_time, duration,
    wall)``."""
    n = step.size
    t = np.empty(n)
    for i in range(n):
        t[i] = step[i] * dt + offset[i]
    counted = np.empty(n, np.bool_)
    for i in range(n):
        counted[i] = eps[i] * u[i] >= floor
    ends = _ends(t, start)
    first_mask = _first_mask(step, offset, u, t, ends, counted, dt, pressed, rule, wall)
    # the collisions and each impact's collision
    n_first = 0
    impact_collision = np.empty(n, np.int64)
    for i in range(n):
        if first_mask[i]:
            n_first += 1
        impact_collision[i] = n_first - 1
    first = np.empty(n_first, np.int64)
    c = 0
    for i in range(n):
        if first_mask[i]:
            first[c] = i
            c += 1
    # the sticking phases that begin inside each collision [t_first, t_next_first)
    m = start.size
    cum = np.empty(m + 1)
    cum[0] = 0.0
    for p in range(m):
        cum[p + 1] = cum[p] + (end[p] - start[p])
    # the collisions before t0 are dropped (times increase: a prefix)
    n_before = 0
    while n_before < n_first and t[first[n_before]] < t0:
        n_before += 1
    k = n_first - n_before
    out_first = first[n_before:].copy()
    rebounds = np.zeros(k, np.int64)
    stuck = np.empty(k, np.bool_)
    stick_time = np.empty(k)
    duration = np.empty(k)
    lo = 0
    if k:
        while lo < m and start[lo] < t[first[n_before]]:
            lo += 1
    for c in range(n_before, n_first):
        a = first[c]
        b = first[c + 1] if c + 1 < n_first else n      # the next collision's first impact
        hi = lo
        if b < n:
            while hi < m and start[hi] < t[b]:
                hi += 1
        else:
            hi = m
        o = c - n_before
        stuck[o] = hi > lo
        stick_time[o] = cum[hi] - cum[lo]
        if hi > lo:
            duration[o] = end[hi - 1] - t[a]
        else:
            duration[o] = t[b - 1] - t[a]
        r = 0
        for i in range(a, b):
            if counted[i]:
                r += 1
        rebounds[o] = r
        lo = hi
    for i in range(n):
        impact_collision[i] = max(impact_collision[i] - n_before, -1)
    time_first, step_first, offset_first, u_first, wall_first = _at_firsts(
        out_first, t, step, offset, u, wall)
    n_counted = 0
    for i in range(n):
        if counted[i]:
            n_counted += 1
    return (n_counted, out_first, impact_collision, step_first, offset_first, time_first, u_first,
            rebounds, stuck, stick_time, duration, wall_first)


@kernel
def firsts(step, offset, u, start, dt, eps, floor, pressed, rule, wall, t0):
    """The collisions at or after ``t0`` as `group` finds them, reduced to what a map cell
    reads at each precision check: of each one's first impact its index, instant, split
    instant, velocity and wall, and whether a sticking phase begins before the next
    collision (`group`'s ``first, time, step, offset, velocity, wall, stuck``: the same mask
    and merge, without the other fields). ``eps`` holds each impact's restitution (its
    wall's law at its speed: it rebounds at ``eps[i] u[i]``), as in `group`. The physical rule's
    backward scan is `_chatter_firsts` with the links formed on the way (no array of
    them)."""
    n = step.size
    t = np.empty(n)
    for i in range(n):
        t[i] = step[i] * dt + offset[i]
    ends = _ends(t, start)
    if rule == PHYSICAL:
        first_mask = np.ones(n, np.bool_)
        next_end, next_break = n, n
        for j in range(n - 1, -1, -1):
            if ends[j]:
                next_end = j
            elif j == n - 1 or not pressed[j]:
                next_break = j
            elif next_end < n and next_break > next_end:
                first_mask[j + 1] = False
        for i in range(1, n):
            if wall[i] != wall[i - 1]:
                first_mask[i] = True
    else:
        counted = np.empty(n, np.bool_)
        for i in range(n):
            counted[i] = eps[i] * u[i] >= floor
        first_mask = _first_mask(step, offset, u, t, ends, counted, dt, pressed, rule, wall)
        if rule == REBOUNDS and not counted.any():
            first_mask[:] = False       # no rebound reaches the floor: no event at all
    kept = np.empty(n + 1, np.int64)
    n_first = 0
    for i in range(n):          # times increase: the dropped ones are a prefix
        kept[n_first] = i
        n_first += first_mask[i] and t[i] >= t0
    first = kept[:n_first].copy()
    stuck = np.empty(n_first, np.bool_)
    m = start.size
    lo = 0
    if n_first:
        while lo < m and start[lo] < t[first[0]]:
            lo += 1
    for c in range(n_first):
        b = first[c + 1] if c + 1 < n_first else n
        hi = lo
        if b < n:
            while hi < m and start[hi] < t[b]:
                hi += 1
        else:
            hi = m
        stuck[c] = hi > lo
        lo = hi
    time_first, step_first, offset_first, u_first, wall_first = _at_firsts(
        first, t, step, offset, u, wall)
    return first, time_first, step_first, offset_first, u_first, wall_first, stuck


@kernel
def motion_pass(t, step, offset, dt, scale, stuck, walls, refine, window, lengths, periods,
                lowers, n_motions, edges):
    """One pass of `stats.motion_statistics` over the collisions at ``t`` (split ``step,
    offset``): the intervals ``z`` (``Collisions.intervals``), their ratios ``z * scale``
    (``scale = beta / (2 pi)``, `stats.interval_ratio`), `label`, and with ``edges`` (not
    empty) `at_edges`; then each class's intervals gathered in time order, ``gathered[
    bounds[c] : bounds[c + 1]]`` being ``z[classes == c]`` (numpy sums them as it sums the
    boolean selection: the same values in the same order). ``stuck`` and ``walls`` are per
    interval (``stuck`` empty and ``refine`` False: not given, the classes are the labels;
    ``walls`` empty: one-wall motions only)."""
    n = max(t.size - 1, 0)
    z = np.empty(n)
    ratio = np.empty(n)
    for i in range(n):
        z[i] = float(step[i + 1] - step[i]) * dt + (offset[i + 1] - offset[i])
        ratio[i] = z[i] * scale
    labels, classes, switches = label(ratio, window, lengths, periods, lowers, walls, stuck,
                                      n_motions)
    n_classes = 2 * n_motions if refine else n_motions
    covered = np.zeros((n_classes, edges.size))
    if n > 0 and edges.size:
        covered = at_edges(t, z, classes, n_classes, edges)
    bounds = np.zeros(n_classes + 1, np.int64)
    for i in range(n):
        if classes[i] >= 0:
            bounds[classes[i] + 1] += 1
    for c in range(n_classes):
        bounds[c + 1] += bounds[c]
    gathered = np.empty(bounds[n_classes])
    fill = bounds[:n_classes].copy()
    for i in range(n):
        c = classes[i]
        if c >= 0:
            gathered[fill[c]] = z[i]
            fill[c] += 1
    return z, labels, switches, covered, gathered, bounds


@kernel
def rule_fractions(step, offset, u, start, dt, eps, floor, pressed, rules, wall, t0, scale,
                   walls, window, lengths, periods, lowers, n_motions):
    """For each rule code of ``rules``: `firsts` at or after ``t0``, then `motion_pass` of
    its collisions with their ``stuck`` flags (and walls when ``walls``), no edges; returns
    per rule ``(gathered, bounds)`` stacked: the intervals of every class of every rule in
    one array, ``bounds`` of shape (rules, classes + 1) into it. One call for the rules a
    map cell reports besides its own (`MotionTally.rule_probabilities`)."""
    n_classes = 2 * n_motions
    parts = []
    bounds = np.zeros((rules.size, n_classes + 1), np.int64)
    total = 0
    for q in range(rules.size):
        _, time, c_step, c_offset, _, c_wall, stuck = firsts(
            step, offset, u, start, dt, eps, floor, pressed, rules[q], wall, t0)
        n = max(time.size - 1, 0)
        w = c_wall[:n].copy() if walls else np.zeros(0, np.int8)
        _, _, _, _, gathered, b = motion_pass(time, c_step, c_offset, dt, scale,
                                               stuck[:n].copy(), w, True, window, lengths,
                                               periods, lowers, n_motions, np.zeros(0))
        parts.append(gathered)
        for c in range(n_classes + 1):
            bounds[q, c] = b[c] + total
        total += gathered.size
    out = np.empty(total)
    o = 0
    for g in parts:
        out[o:o + g.size] = g
        o += g.size
    return out, bounds


@kernel
def residence(edges, states, n_states):
    """`stats.residence_statistics` in one pass: ``(mean, stderr, n_stretches, n_censored,
    time, count, rate)``, each sum taken in the order ``numpy.bincount`` takes it (the
    pieces, or the stretches, in time order)."""
    k = states.size
    time = np.zeros(n_states)
    for i in range(k):
        time[states[i]] += edges[i + 1] - edges[i]
    # stretches: runs of one state
    n_runs = 0
    for i in range(k):
        if i == 0 or states[i] != states[i - 1]:
            n_runs += 1
    start = np.empty(n_runs, np.int64)
    r = 0
    for i in range(k):
        if i == 0 or states[i] != states[i - 1]:
            start[r] = i
            r += 1
    n = np.zeros(n_states, np.int64)
    n_censored = np.zeros(n_states, np.int64)
    total = np.zeros(n_states)
    length = np.empty(n_runs)
    count = np.zeros((n_states, n_states), np.int64)
    for r in range(n_runs):
        stop = start[r + 1] if r + 1 < n_runs else k
        length[r] = edges[stop] - edges[start[r]]
        who = states[start[r]]
        if r == 0 or r == n_runs - 1:
            n_censored[who] += 1
        else:
            n[who] += 1
            total[who] += length[r]
        if r > 0:
            count[states[start[r - 1]], who] += 1
    mean = np.empty(n_states)
    for s in range(n_states):
        mean[s] = total[s] / max(n[s], 1) if n[s] > 0 else np.nan
    dev = np.zeros(n_states)
    for r in range(1, n_runs - 1):
        who = states[start[r]]
        d = length[r] - mean[who]
        dev[who] += d * d
    stderr = np.empty(n_states)
    for s in range(n_states):
        stderr[s] = (np.sqrt(dev[s] / max(n[s] - 1, 1) / max(n[s], 1)) if n[s] > 1
                     else np.nan)
    rate = np.empty((n_states, n_states))
    for a in range(n_states):
        for b in range(n_states):
            rate[a, b] = count[a, b] / time[a] if time[a] > 0.0 else np.nan
    return mean, stderr, n, n_censored, time, count, rate


@kernel
def label(ratio, window, lengths, periods, lowers, walls, stuck, n_motions):
    """Labels, classes and switches of the intervals (``stats.motions._classify``, then
    ``_refine(labels, _with_sticking(...))``, ``count_motion_switches``).

    ``lengths, periods, lowers``: per motion its intervals m, periods n and collisions at
    the lower wall (-1: a pair, any wall); ``walls`` the wall of each interval's first
    collision (read only for triples); ``stuck`` per interval (empty: no refinement, classes
    are the labels). The greedy scan of the reference's definition: at the first unassigned
    interval that starts some matching group, the first motion that matches claims its
    intervals."""
    n = ratio.size
    labels = np.full(n, -1, np.int64)
    classes = np.full(n, -1, np.int64)
    refine = stuck.size == n and n > 0
    j = 0
    while j < n:
        chosen = -1
        for i in range(n_motions):
            m = lengths[i]
            if j + m > n:
                continue
            if m == 1:
                ok = abs(ratio[j] - periods[i]) < window
            else:
                top = ratio[j]
                total = ratio[j]
                for q in range(j + 1, j + m):
                    top = max(top, ratio[q])
                    total = total + ratio[q]
                ok = top < periods[i] - window and abs(total - periods[i]) < window
            if ok and lowers[i] >= 0:
                count = 0
                for q in range(j, j + m):
                    if walls[q] == 1:
                        count += 1
                ok = count == lowers[i]
            if ok:
                chosen = i
                break
        if chosen < 0:
            j += 1
            continue
        m = lengths[chosen]
        sticks = False
        if refine:
            for q in range(j, j + m):
                sticks = sticks or stuck[q]
        for q in range(j, j + m):
            labels[q] = chosen
            classes[q] = chosen + n_motions if sticks else chosen
        j += m
    switches = 0
    last = -1
    for q in range(n):
        if labels[q] >= 0:
            if last >= 0 and labels[q] != last:
                switches += 1
            last = labels[q]
    return labels, classes, switches


@kernel
def at_edges(t, z, classes, n_classes, edges):
    """``stats.motions._at_edges``: the time each class covered from the first collision to
    each edge (``edges`` ascending), the cumulative sums taken sequentially as ``numpy.cumsum``
    of ``z * onehot`` takes them, the part of the interval an edge cuts added to its class."""
    n = z.size
    out = np.zeros((n_classes, edges.size))
    s = np.zeros(n_classes)
    q = 0           # the intervals summed so far: those before j
    count = 0       # collisions at or before the edge
    for k in range(edges.size):
        e = edges[k]
        while count < t.size and t[count] <= e:
            count += 1
        j = min(max(count - 1, 0), t.size - 1)
        while q < j:
            c = classes[q]
            if c >= 0:
                s[c] = s[c] + z[q]
            q += 1
        if not e > t[0]:
            continue            # before the first collision: 0
        jj = min(j, n - 1)
        cut = min(e - t[j], z[jj])
        for c in range(n_classes):
            extra = cut if (j < n and classes[jj] == c) else 0.0
            out[c, k] = s[c] + extra
    return out
