"""Residence times and switching rates of a labelled record (`stats.residence`)."""
import numpy as np
import pytest

from vibroimpact import stats


def test_residence_times_of_a_known_sequence_are_exact():
    """Pieces merge into stretches; the first and last stretches are cut, left out of the mean
    and counted apart; the means and the spread are those of the complete stretches."""
    #          cut  |  0 (1+2)  | 1 | 0 |  2  | 1 (2+2) |  0  | cut
    states = [2,       0, 0,      1,  0,  2,    1, 1,     0,    2]
    length = [5.0,     1.0, 2.0,  4.0, 6.0, 0.5, 2.0, 2.0, 9.0, 7.0]
    edges = np.concatenate([[10.0], 10.0 + np.cumsum(length)])
    r = stats.residence_statistics(edges, states, 3)
    # complete stretches: state 0: 3, 6, 9; state 1: 4, 4; state 2: 0.5
    assert r.n_stretches.tolist() == [3, 2, 1]
    assert r.n_censored.tolist() == [0, 0, 2]
    np.testing.assert_allclose(r.mean, [6.0, 4.0, 0.5], rtol=0, atol=1e-12)
    np.testing.assert_allclose(r.stderr[:2], [3.0 / np.sqrt(3), 0.0], rtol=0, atol=1e-12)
    assert np.isnan(r.stderr[2])                       # one stretch: no spread
    np.testing.assert_allclose(r.time, [18.0, 8.0, 12.5], rtol=0, atol=1e-12)
    # switches 2->0, 0->1, 1->0, 0->2, 2->1, 1->0, 0->2
    assert r.count.tolist() == [[0, 1, 2], [2, 0, 0], [1, 1, 0]]
    np.testing.assert_allclose(r.rate, r.count / r.time[:, None], rtol=0, atol=0)
    assert np.diag(r.rate).tolist() == [0.0, 0.0, 0.0]


def test_a_record_in_one_state_is_one_cut_stretch():
    r = stats.residence_statistics([0.0, 1.0, 3.0], [1, 1], 3)
    assert r.n_stretches.tolist() == [0, 0, 0] and r.n_censored.tolist() == [0, 1, 0]
    assert np.isnan(r.mean).all() and r.time.tolist() == [0.0, 3.0, 0.0]
    assert np.isnan(r.rate[[0, 2]]).all() and r.rate[1].tolist() == [0.0, 0.0, 0.0]
    pi = stats.stationary_distribution(r.rate)
    assert pi.tolist() == [0.0, 1.0, 0.0]


def test_the_cut_ends_are_censored_whatever_the_state():
    """The stretch holding the start and the one holding the end are cut, even when they are
    of a state whose other stretches are complete: a long stretch cut by the end does not
    shorten the mean."""
    edges = [0.0, 1.0, 3.0, 4.0, 6.0, 7.0, 107.0]
    states = [0, 1, 0, 1, 0, 1]
    r = stats.residence_statistics(edges, states, 2)
    assert r.n_censored.tolist() == [1, 1] and r.n_stretches.tolist() == [2, 2]
    np.testing.assert_allclose(r.mean, [1.0, 2.0])        # not 2 + 100 in the mean of 1
    assert r.time.tolist() == [3.0, 104.0]                   # the cut ones included


def test_label_pieces_keeps_the_intervals_between_the_first_and_last_collision():
    """Before the first and after the last collision the type is unknown: no piece; an
    unclassified interval is "none"; no interval at all: the record is one piece of none."""
    edges, states = stats.label_pieces([2.0, 3.0, 5.0, 6.0], [0, -1, 1], 1.0, 8.0, 2)
    assert edges.tolist() == [2.0, 3.0, 5.0, 6.0] and states.tolist() == [0, 2, 1]
    edges, states = stats.label_pieces([], [], 1.0, 8.0, 2)
    assert edges.tolist() == [1.0, 8.0] and states.tolist() == [2]
    edges, states = stats.label_pieces([4.0], [], 1.0, 8.0, 2)     # one collision: no interval
    assert edges.tolist() == [1.0, 8.0] and states.tolist() == [2]
    r = stats.residence_statistics([4.0], [], 3)                    # no piece: nothing known
    assert r.n_stretches.tolist() == [0, 0, 0] and np.isnan(r.rate).all()
    with pytest.raises(ValueError, match="one more"):
        stats.label_pieces([1.0, 2.0], [0, 0], 0.0, 3.0, 2)


def _telegraph(rate_01, rate_10, total, seed):
    """A two-state Markov (telegraph) record: exponential stays, rates known."""
    rng = np.random.default_rng(seed)
    n = int(3 * total * max(rate_01, rate_10)) + 100
    state0 = rng.integers(2)
    stay = rng.exponential(1.0, n)
    which = (state0 + np.arange(n)) % 2
    stay = stay / np.where(which == 0, rate_01, rate_10)
    edges = np.concatenate([[0.0], np.cumsum(stay)])
    keep = np.searchsorted(edges, total)
    edges = np.append(edges[:keep], total)
    return edges, which[:keep]


def test_rates_of_a_telegraph_sequence_match_the_known_rates():
    """Rates within 4 Poisson errors (sqrt(count) / time); mean residence times 1/rate within
    4 stderr; the stationary distribution a / (a + b) within 4 of its error."""
    a, b = 0.2, 0.05                 # 0 -> 1 and 1 -> 0
    edges, states = _telegraph(a, b, 40_000.0, 7)
    r = stats.residence_statistics(edges, states, 2)
    for (i, j), true in {(0, 1): a, (1, 0): b}.items():
        err = np.sqrt(r.count[i, j]) / r.time[i]
        assert abs(r.rate[i, j] - true) < 4 * err, (i, j, r.rate[i, j], err)
    np.testing.assert_array_less(np.abs(r.mean - [1 / a, 1 / b]), 4 * r.stderr)
    # exponential stays: their std equals their mean (a Markov record)
    np.testing.assert_allclose(r.stderr * np.sqrt(r.n_stretches), r.mean, rtol=0.1)
    pi = stats.stationary_distribution(r.rate)
    assert pi.sum() == pytest.approx(1.0)
    # pi_1 = a / (a + b); error from the rates' relative Poisson errors
    rel = np.hypot(1 / np.sqrt(r.count[0, 1]), 1 / np.sqrt(r.count[1, 0]))
    assert abs(pi[1] - a / (a + b)) < 4 * rel * pi[0] * pi[1]


def test_the_stationary_distribution_is_the_time_fractions_up_to_the_ends():
    """For any record the rate matrix's stationary distribution and the fractions of time
    differ by O(1/switches): switches in and out of a state differ by at most one."""
    rng = np.random.default_rng(3)
    states = rng.integers(0, 4, 5000)
    states[rng.random(5000) < 0.3] = 3
    edges = np.concatenate([[0.0], np.cumsum(rng.gamma(0.5, 2.0, 5000))])
    r = stats.residence_statistics(edges, states, 4)
    pi = stats.stationary_distribution(r.rate)
    frac = r.time / r.time.sum()
    assert np.abs(pi - frac).max() < 2.0 / r.count.sum()


def test_stationary_distribution_is_nan_when_not_unique():
    rate = np.array([[0.0, 0.0, 0.0], [0.0, 0.0, 0.0], [1.0, 1.0, 0.0]])
    assert np.isnan(stats.stationary_distribution(rate)).all()


def test_bad_input_is_refused():
    with pytest.raises(ValueError, match="one more"):
        stats.residence_statistics([0.0, 1.0], [0, 0], 2)
    with pytest.raises(ValueError, match="states must lie"):
        stats.residence_statistics([0.0, 1.0], [2], 2)
    with pytest.raises(ValueError, match="non-decreasing"):
        stats.residence_statistics([0.0, 1.0, 0.5], [0, 1], 2)


# --- is the sequence Markov? (stats.markov_residence_check, stats.jump_chain_independence) ---

def _markov_chain(rates, total, seed):
    """A continuous-time Markov chain with off-diagonal ``rates``: exponential stays of mean
    1 / (row sum), the next state drawn by the row's rates, independent of the past."""
    rng = np.random.default_rng(seed)
    rates = np.asarray(rates, dtype=float)
    out = rates.sum(axis=1)
    t, state, edges, states = 0.0, 0, [0.0], []
    while t < total:
        t += rng.exponential(1.0 / out[state])
        edges.append(min(t, total))
        states.append(state)
        state = rng.choice(len(out), p=rates[state] / out[state])
    return np.array(edges), np.array(states)


def test_a_simulated_markov_chain_passes_both_checks():
    """Three states, unequal rates: every state's stretches have CV 1 within 2/sqrt(n), and
    the next state does not depend on the previous one (p > 0.01; seeded)."""
    rates = [[0.0, 0.3, 0.1], [0.05, 0.0, 0.05], [0.5, 0.2, 0.0]]
    edges, states = _markov_chain(rates, 30_000.0, 11)
    r = stats.residence_statistics(edges, states, 3)
    check = stats.markov_residence_check(r.mean, r.stderr, r.n_stretches)
    assert (r.n_stretches > 300).all()
    assert check.markov.tolist() == [1.0, 1.0, 1.0], check
    assert (np.abs(check.cv - 1.0) <= 2 / np.sqrt(r.n_stretches)).all()
    statistic, dof, p = stats.jump_chain_independence(states, 3)
    assert dof == 3 and p > 0.01, (statistic, p)


def test_a_fixed_length_sequence_fails():
    """Every stretch as long as the others: CV 0, many standard deviations below 1; a cycle
    A B A C A B ...: from A the next state is set by the previous one."""
    states = np.tile([0, 1, 0, 2], 100)
    edges = np.arange(states.size + 1, dtype=float) * 3.0
    r = stats.residence_statistics(edges, states, 3)
    check = stats.markov_residence_check(r.mean, r.stderr, r.n_stretches)
    np.testing.assert_allclose(check.cv, 0.0, atol=1e-12)
    assert check.markov.tolist() == [0.0, 0.0, 0.0]
    statistic, dof, p = stats.jump_chain_independence(states, 3)
    assert dof == 1 and p < 1e-10


def test_stays_in_whole_units_are_markov_when_geometric():
    """A motion group that repeats with probability 1/2 whatever came before: a geometric
    number of units (mean 2 units, CV sqrt(1/2)). Markov in units of its step; judged in
    continuous time (unit 0) it would look too regular. Too few stretches: not judged."""
    rng = np.random.default_rng(5)
    stays = rng.geometric(0.5, 2000).astype(float)
    mean, sd, n = stays.mean(), stays.std(ddof=1), stays.size
    stepped = stats.markov_residence_check(mean, sd / np.sqrt(n), n, unit=1.0)
    assert stepped.cv_markov == pytest.approx(np.sqrt(1 - 1 / mean))
    assert stepped.markov == 1.0 and abs(stepped.z) < 2
    assert stats.markov_residence_check(mean, sd / np.sqrt(n), n).markov == 0.0
    few = stats.markov_residence_check(mean, sd / np.sqrt(9), 9, unit=1.0)
    assert np.isnan(few.markov)


def test_two_states_carry_no_jump_chain_information():
    statistic, dof, p = stats.jump_chain_independence([0, 1, 0, 1, 1, 0], 2)
    assert dof == 0 and np.isnan(p)
