"""C4-smooth building blocks for the gait profiles.

Every joint trajectory of the foot is assembled from these pieces so that position is continuous through its
4th derivative everywhere (anchors §4: C2 joins cap strapdown consistency at ~9 mm per 10 s).

A *derivative stack* is an array ``(5, N)``: row ``j`` holds the j-th time derivative at N sample times.
"""

from __future__ import annotations

import functools

import numpy as np
from numpy.polynomial import polynomial as P

ORDER = 4  # highest derivative kept continuous
NDER = ORDER + 1

# s^5 (126 - 420 s + 540 s^2 - 315 s^3 + 70 s^4): 0 -> 1 on [0, 1], derivatives 1..4 vanish at both ends
SMOOTHSTEP = np.array([0, 0, 0, 0, 0, 126, -420, 540, -315, 70], float)
# 256 s^4 (1-s)^4: bump with peak 1 at s = 1/2, derivatives 0..3 vanish at both ends (a C3 velocity pulse
# whose integral, a displacement, is C4)
PULSE = 256.0 * P.polymul(P.polypow([0, 1], 4), P.polypow([1, -1], 4))
# 1024 s^5 (1-s)^5: bump with peak 1 at s = 1/2, derivatives 0..4 vanish at both ends (a C4 displacement)
LIFT = 1024.0 * P.polymul(P.polypow([0, 1], 5), P.polypow([1, -1], 5))
# double integral of SMOOTHSTEP: a displacement whose 2nd derivative rises C4 from 0 to 1 over [0, 1] (value 3/22
# and derivative 1/2 at s = 1)
RELEASE = P.polyint(SMOOTHSTEP, 2)
# s^5 (1-s)^5: derivatives 0..4 vanish at both ends; times a quadratic, the shapes :func:`lead` draws from
LEAD_ENVELOPE = P.polymul(P.polypow([0, 1], 5), P.polypow([1, -1], 5))
LEAD_PHASES = np.array([0.25, 0.5, 0.75])  # phases at which :func:`lead` takes its values
PULSE_AREA = float(P.polyval(1.0, P.polyint(PULSE)))  # integral of PULSE over [0, 1] = 256 * B(5, 5)


class Piecewise:
    """A scalar C4 function of time, piecewise polynomial (:class:`scipy.interpolate.PPoly`'s layout), held
    constant outside its breakpoint range.

    Parameters
    ----------
    coef : (k+1, m) coefficients of each of the m pieces in powers of ``t - breaks[i]``, highest power first.
    breaks : (m+1,) s, increasing breakpoints.
    """

    def __init__(self, coef: np.ndarray, breaks: np.ndarray):
        self.coef = np.asarray(coef, float)
        self.breaks = np.asarray(breaks, float)
        self.t0 = float(self.breaks[0])
        self.t1 = float(self.breaks[-1])
        self._left = self.breaks[:-1]  # left end of each piece (s)
        self._interior = self.breaks[1:-1]  # breakpoints between pieces (s)

    @functools.cached_property
    def before(self) -> float:
        """The value held before the breakpoint range."""
        return float(power_sum(self.coef[:, 0], 0.0))

    @functools.cached_property
    def after(self) -> float:
        """The value held after the breakpoint range."""
        return float(power_sum(self.coef[:, -1], self.t1 - float(self.breaks[-2])))

    @functools.cached_property
    def _coef(self) -> np.ndarray:
        """(k+1, 5, m) coefficients of the function and its derivatives 1..4 (:func:`derivative_table`)."""
        return derivative_table(self.coef)

    @property
    def pp(self):
        """The function on its breakpoint range as a :class:`scipy.interpolate.PPoly` (for checks)."""
        from scipy.interpolate import PPoly

        return PPoly(self.coef, self.breaks)

    def stack(self, t: np.ndarray) -> np.ndarray:
        """Derivative stack (5, N) at times ``t`` (s). Outside the range: held value, zero derivatives.

        All five rows come from one Horner pass over the piece's coefficients (PPoly evaluates one derivative
        per call, and the foot model asks for thousands of short stacks)."""
        t = np.asarray(t, float).ravel()
        out = np.zeros((NDER, t.size))
        inside = (t >= self.t0) & (t <= self.t1)
        if inside.any():
            ti = t[inside]
            if self._interior.size:  # each row of coefficients gathered for the samples as Horner needs it
                piece = np.searchsorted(self._interior, ti, side="right")  # the last piece includes its right end
                out[:, inside] = _horner(self._coef, piece, ti - self._left[piece])
            else:  # one piece: its coefficients broadcast over the samples
                out[:, inside] = _horner(self._coef, None, ti - self._left[0])
        out[0, t < self.t0] = self.before
        out[0, t > self.t1] = self.after
        return out


def derivative_table(coef: np.ndarray) -> np.ndarray:
    """(k+1, 5, m) coefficients, highest power first and zero-padded at the top, of the m pieces' polynomials
    ``coef`` (k+1, m) and their derivatives 1..4."""
    order = coef.shape[0]
    powers = np.arange(order - 1, -1, -1, dtype=float)[:, None]  # power of each row of coef
    table = np.zeros((order, NDER, coef.shape[1]))
    table[:, 0] = coef
    for j in range(1, NDER):  # d/dx c_r x^p_r = c_r p_r x^(p_r - 1): the term moves one row down
        table[1:, j] = (table[:, j - 1] * powers)[:-1]
    return table


def _horner(coef: np.ndarray, piece: np.ndarray | None, local: np.ndarray) -> np.ndarray:
    """(5, n) derivative stacks from the derivative coefficient table ``coef`` (k+1, 5, m) (highest power
    first) of piece ``piece[i]`` (None: the only piece) at ``local[i]`` s from its left end: one Horner pass,
    each row of coefficients gathered for the samples as it is needed."""
    if piece is None:
        rows = iter(coef)
    elif np.all(piece[1:] >= piece[:-1]):  # samples in the order of the pieces: each row's columns repeated
        counts = np.bincount(piece, minlength=coef.shape[2])
        rows = (np.repeat(row, counts, axis=1) for row in coef)
    else:
        rows = (np.take(row, piece, axis=1) for row in coef)
    value = np.empty((NDER, local.size))
    value[:] = next(rows)
    for c in rows:
        value *= local
        value += c
    return value


class PieceTable:
    """Many :class:`Piecewise` functions of the same degree packed for one evaluation in which every sample
    names its function: the stacks of each, bit for bit, in a handful of numpy calls instead of a handful per
    function.

    Parameters
    ----------
    functions : sequence of Piecewise, all with the same number of coefficients per piece.
    """

    def __init__(self, functions):
        orders = {f.coef.shape[0] for f in functions}
        if len(orders) != 1:
            raise ValueError(f"a PieceTable packs functions of one degree; got {len(orders)} ({sorted(orders)})")
        self._coef = derivative_table(np.concatenate([f.coef for f in functions], axis=1))  # (k+1, 5, pieces)
        self._left = np.concatenate([f._left for f in functions])
        counts = np.array([f.coef.shape[1] for f in functions])
        self._first = np.concatenate([[0], np.cumsum(counts)[:-1]])  # each function's first piece
        # interior breakpoints of each function, padded with +inf: (functions, most pieces - 1)
        self._interior = np.full((len(functions), counts.max() - 1), np.inf)
        for i, f in enumerate(functions):
            self._interior[i, :f._interior.size] = f._interior
        self.t0 = np.array([f.t0 for f in functions])
        self.t1 = np.array([f.t1 for f in functions])
        self.before = power_sum(np.stack([f.coef[:, 0] for f in functions], axis=1), 0.0)  # held values
        self.after = power_sum(np.stack([f.coef[:, -1] for f in functions], axis=1),
                               self.t1 - np.array([f.breaks[-2] for f in functions]))
        nonzero = np.logical_or.reduceat(np.any(self._coef[:, 0] != 0.0, axis=0), self._first)
        self._live = np.flatnonzero(nonzero)  # the functions not identically zero

    def stack(self, t: np.ndarray, function: np.ndarray) -> np.ndarray:
        """(5, N) derivative stacks at increasing times ``t`` (N,) s, sample i of function ``function[i]``
        (non-decreasing): what that function's :meth:`Piecewise.stack` gives there."""
        functions = np.arange(self.t0.size)
        out = np.zeros((NDER, t.size))
        self.add_to(out, t, np.searchsorted(function, functions, side="left"),
                    np.searchsorted(function, functions, side="right"))
        return out

    def add_to(self, out: np.ndarray, t: np.ndarray, start: np.ndarray, stop: np.ndarray) -> None:
        """``out`` (5, N) += the stack of function j on samples ``start[j]:stop[j]`` of the increasing times
        ``t`` (N,) s, for every j (the runs disjoint and in order): inside a function's window its whole
        stack, outside its held value in row 0; equal to adding its :meth:`Piecewise.stack` whenever ``out``
        holds no -0.0 (so a function that is identically zero, whose stack is +-0, is skipped)."""
        live = self._live
        start, stop = start[live], stop[live]
        lo = np.clip(np.searchsorted(t, self.t0[live], side="left"), start, stop)  # first sample with t >= t0
        hi = np.clip(np.searchsorted(t, self.t1[live], side="right"), lo, stop)  # first sample with t > t1
        inside = _ranges(lo, hi)
        if inside.size:
            ti, fi = t[inside], np.repeat(live, hi - lo)
            # interior breakpoints <= t (Piecewise's searchsorted side="right"): the last piece includes its end
            piece = self._first[fi] + (ti[:, None] >= self._interior[fi]).sum(axis=1)
            value = _horner(self._coef, piece, ti - self._left[piece])
            if inside.size == out.shape[1]:  # every sample inside its function's window
                out += value
            else:
                out[:, inside] += value
        out[0, _ranges(start, lo)] += np.repeat(self.before[live], lo - start)
        out[0, _ranges(hi, stop)] += np.repeat(self.after[live], stop - hi)


def _ranges(start: np.ndarray, stop: np.ndarray) -> np.ndarray:
    """The indices start[j], ..., stop[j] - 1 of every j, concatenated."""
    counts = stop - start
    return np.arange(counts.sum()) + np.repeat(start - (np.cumsum(counts) - counts), counts)


def accumulate(out: np.ndarray, t: np.ndarray, t0, t1, stack) -> None:
    """Add K functions, each held constant outside its own window [t0[j], t1[j]] (derivatives zero there), to
    ``out`` in turn, evaluating each only on the samples in its window.

    The windows are disjoint and in increasing order. Inside its window a function's stack is added; outside,
    row 0 gets its held value there unless that value is +0.0 (adding +0.0 to a number that is not -0.0 changes
    nothing). Each sample gets the held values and the stacks in the order of the functions, so the result
    equals ``for j: out += stack_j(t)`` bit for bit whenever ``out`` holds no -0.0, as in any sum started from
    ``np.zeros``.

    Parameters
    ----------
    out : (..., 5, N) derivative stacks, updated in place.
    t : (N,) s, increasing sample times.
    t0, t1 : (K,) or scalar, s: the windows outside which the functions are constant.
    stack : callable mapping increasing times (n,) s and the function of each (n,) int, non-decreasing (0 to
        K-1), to (..., 5, n) derivative stacks.
    """
    t0, t1 = np.atleast_1d(np.asarray(t0, float)), np.atleast_1d(np.asarray(t1, float))
    if np.any(t0[1:] <= t1[:-1]):
        raise ValueError("accumulate: the windows must be disjoint and in increasing order")
    k = t0.size
    if k == 0:
        return
    lo, hi = np.searchsorted(t, t0, side="left"), np.searchsorted(t, t1, side="right")
    inside = _ranges(lo, hi)
    functions = np.arange(k)
    # each function just before and just after its window (its held values), then on its window
    held = stack(np.stack([np.nextafter(t0, -np.inf), np.nextafter(t1, np.inf)], axis=1).ravel(),
                 np.repeat(functions, 2))[..., 0, :]
    held = held.reshape(-1, k, 2)
    adds = np.any((held != 0.0) | np.signbit(held), axis=0)  # (K, 2): a held value other than +0.0
    for j in np.flatnonzero(adds[:, 1] & (hi < t.size)):  # a sample adds the held values of the windows before
        out[..., 0, hi[j]:] += held[:, j, 1].reshape(out.shape[:-2] + (1,))  # it in order,
    out[..., inside] += stack(t[inside], np.repeat(functions, hi - lo))  # its own window's stack,
    for j in np.flatnonzero(adds[:, 0] & (lo > 0)):  # then the later ones' values before them
        out[..., 0, :lo[j]] += held[:, j, 0].reshape(out.shape[:-2] + (1,))


def _hermite_tail() -> np.ndarray:
    """(5, 5) matrix M with a[5:] = M (b - E a[:5]) for the degree-9 Hermite on [0, 1] (see :func:`hermite`)."""
    from math import factorial

    k = np.arange(2 * NDER)
    rows = np.array([[factorial(n) / factorial(n - j) if n >= j else 0.0 for n in k] for j in range(NDER)])
    return np.linalg.inv(rows[:, NDER:]), rows[:, :NDER]


_TAIL_INVERSE, _HEAD = _hermite_tail()
_FACTORIALS = np.array([1.0, 1.0, 2.0, 6.0, 24.0])
_POWERS = np.arange(2 * NDER)  # powers of u in the degree-9 Hermite


def hermite(knots: np.ndarray, stacks: np.ndarray) -> Piecewise:
    """Piecewise degree-9 polynomial through ``knots`` (s) matching value and derivatives 1..4 at each knot.

    On each interval of length h, with u = (t - t_i) / h the polynomial is ``sum_n a_n u^n``: the first five
    coefficients are the left knot's derivatives ``a_j = y_j h^j / j!``; the last five solve the five
    conditions at the right knot, one constant 5 x 5 system for every interval.

    Parameters
    ----------
    knots : (K,) increasing times (s).
    stacks : (K, 5) value and derivatives 1..4 at each knot (unit/s^j).
    """
    knots = np.asarray(knots, float)
    stacks = np.asarray(stacks, float)
    h = (knots[1:] - knots[:-1])[:, None]
    powers = h ** _POWERS[:NDER]
    head = stacks[:-1] * powers / _FACTORIALS
    tail = (stacks[1:] * powers - head @ _HEAD.T) @ _TAIL_INVERSE.T
    a = np.concatenate([head, tail], axis=1)  # (K-1, 10) in u
    coef = a / h ** _POWERS  # in t - t_i
    return Piecewise(coef[:, ::-1].T.copy(), knots)


def power_sum(columns: np.ndarray, local) -> np.ndarray:
    """Values at ``local`` (s from the pieces' left ends; scalar or one per column) of pieces' polynomials
    (``columns`` (k+1,) or (k+1, F): coefficients, highest power first), summed from the lowest power up as
    :class:`scipy.interpolate.PPoly` evaluates it."""
    value, power = 0.0, 1.0
    for c in np.asarray(columns, float)[::-1]:
        value = value + c * power
        power = power * local
    return value


def antiderivative(coef: np.ndarray, breaks: np.ndarray) -> np.ndarray:
    """Coefficients (k+2, m) of the antiderivative, zero at ``breaks[0]`` and continuous, of the piecewise
    polynomial ``coef`` (k+1, m) (highest power first): the arithmetic of ``PPoly.antiderivative``."""
    out = np.zeros((coef.shape[0] + 1, coef.shape[1]))
    out[:-1] = coef / np.arange(coef.shape[0], 0, -1, dtype=float)[:, None]
    for i in range(1, coef.shape[1]):
        out[-1, i] = power_sum(out[:, i - 1], breaks[i] - breaks[i - 1])
    return out


def scaled_poly(shape: np.ndarray, t0: float, duration: float, amplitude: float) -> np.ndarray:
    """(len(shape), 1) coefficients, highest power first, of ``amplitude * shape((t - t0) / duration)`` in
    powers of ``t - t0`` (one piece on [t0, t0 + duration])."""
    powers = duration ** -np.arange(len(shape), dtype=float)
    return (amplitude * shape * powers)[::-1][:, None]


def pulse_displacement(t0: float, duration: float, peak_velocity: float) -> Piecewise:
    """Displacement (m) of a C3 velocity pulse ``peak_velocity * PULSE`` over [t0, t0 + duration].

    The displacement is 0 before ``t0`` and ``peak_velocity * duration * PULSE_AREA`` after the pulse.
    """
    breaks = np.array([t0, t0 + duration])
    return Piecewise(antiderivative(scaled_poly(PULSE, t0, duration, peak_velocity), breaks), breaks)


def plateau_displacement(t_up: float, t_down: float, ramp: float, velocity: float) -> Piecewise:
    """Displacement (m) of a velocity plateau: C4 ramp up on [t_up - ramp, t_up], hold, ramp down on
    [t_down, t_down + ramp]. The velocity is ``velocity`` (m/s) on [t_up, t_down]."""
    coef = np.zeros((len(SMOOTHSTEP), 3))
    coef[:, :1] = scaled_poly(SMOOTHSTEP, t_up - ramp, ramp, velocity)
    coef[-1, 1] = velocity
    coef[:, 2:] = scaled_poly(-SMOOTHSTEP, t_down, ramp, velocity)
    coef[-1, 2] += velocity  # 1 - smoothstep
    breaks = np.array([t_up - ramp, t_up, t_down, t_down + ramp])
    return Piecewise(antiderivative(coef, breaks), breaks)


def lift(t0: float, duration: float, height: float) -> Piecewise:
    """``height * LIFT((t - t0)/duration)`` (m or rad): a C4 bump over [t0, t0 + duration], zero outside."""
    return Piecewise(scaled_poly(LIFT, t0, duration, height), np.array([t0, t0 + duration]))


def release(t1: float, duration: float, accel: float) -> Piecewise:
    """Displacement (m) over [t1 - duration, t1] whose acceleration rises C4 from 0 to ``accel`` (m/s^2) at ``t1``
    (``accel * duration^2 * RELEASE``): zero with its derivatives 1..4 at the start; at ``t1``
    ``3/22 accel duration^2`` m, moving at ``accel duration / 2`` m/s."""
    t0 = t1 - duration
    return Piecewise(scaled_poly(RELEASE, t0, duration, accel * duration**2), np.array([t0, t1]))


def lead(t0: float, duration: float, values) -> Piecewise:
    """A C4 displacement (m) over [t0, t0 + duration], zero outside, equal to ``values`` (3,) m at
    :data:`LEAD_PHASES` of the duration: :data:`LEAD_ENVELOPE` times the quadratic through them, so the
    displacement and its derivatives 1..4 vanish at both ends."""
    quadratic = P.polyfit(LEAD_PHASES, np.asarray(values, float) / P.polyval(LEAD_PHASES, LEAD_ENVELOPE), 2)
    return Piecewise(scaled_poly(P.polymul(LEAD_ENVELOPE, quadratic), t0, duration, 1.0),
                     np.array([t0, t0 + duration]))


def smoothstep(t0: float, duration: float, start: float, end: float) -> Piecewise:
    """A C4 transition from ``start`` to ``end`` over [t0, t0 + duration], held outside."""
    coef = scaled_poly(SMOOTHSTEP, t0, duration, end - start)
    coef[-1, 0] += start
    return Piecewise(coef, np.array([t0, t0 + duration]))


def compose(outer: np.ndarray, inner: np.ndarray) -> np.ndarray:
    """Derivative stack of ``f(g(t))`` (Faà di Bruno to the 4th derivative).

    Parameters
    ----------
    outer : (5, N) f and its derivatives 1..4 with respect to g, evaluated at ``g(t)``.
    inner : (5, N) derivative stack of ``g`` (with respect to t).

    Returns
    -------
    (5, N) derivative stack of ``f(g(t))``.
    """
    f0, f1, f2, f3, f4 = outer
    _, g1, g2, g3, g4 = inner
    return np.stack([
        f0,
        f1 * g1,
        f2 * g1**2 + f1 * g2,
        f3 * g1**3 + 3 * f2 * g1 * g2 + f1 * g3,
        f4 * g1**4 + 6 * f3 * g1**2 * g2 + f2 * (4 * g1 * g3 + 3 * g2**2) + f1 * g4,
    ])


def compose_trig(theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Derivative stacks of ``cos(theta(t))`` and ``sin(theta(t))`` from the stack of ``theta`` (Faà di Bruno).

    Parameters
    ----------
    theta : (5, N) derivative stack of an angle (rad, rad/s, ...).

    Returns
    -------
    cos_stack, sin_stack : (5, N) each.
    """
    c, s = np.cos(theta[0]), np.sin(theta[0])
    return compose(np.stack([c, -s, -c, s, c]), theta), compose(np.stack([s, c, -s, -c, s]), theta)


def product(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Derivative stack of the product of two functions given by their stacks (Leibniz rule)."""
    from math import comb

    return np.stack([sum(comb(n, k) * a[k] * b[n - k] for k in range(n + 1)) for n in range(NDER)])


class Ringing:
    """A damped oscillation ``A exp(-zeta w (t-t0)) sin(w_d (t-t0))`` starting at ``t0``, windowed to stay C4.

    The window rises with a C4 smoothstep over the first period and fades over the last period of a
    duration after which the envelope is below 1 % (ln(100) / (zeta w)).

    Parameters
    ----------
    t0 : s, onset.   freq_hz : Hz, natural frequency.   zeta : damping ratio (0, 1).
    accel : m/s^2, nominal peak acceleration A w^2 (A is the displacement amplitude in m).
    """

    def __init__(self, t0: float, freq_hz: float, zeta: float, accel: float):
        self.t0 = t0
        w = 2 * np.pi * freq_hz
        self.lam = complex(-zeta * w, w * np.sqrt(1 - zeta**2))
        self.amp = accel / w**2
        self.period = 1.0 / freq_hz
        self.duration = max(np.log(100.0) / (zeta * w), 3 * self.period)
        self.t1 = t0 + self.duration  # zero outside [t0, t1]
        self.rise = smoothstep(t0, self.period, 0.0, 1.0)
        self.fade = smoothstep(t0 + self.duration - self.period, self.period, 1.0, 0.0)

    def stack(self, t: np.ndarray) -> np.ndarray:
        t = np.asarray(t, float)
        out = np.zeros((NDER, t.size))
        m = (t >= self.t0) & (t <= self.t1)
        if not m.any():
            return out
        s = t[m] - self.t0
        e = np.exp(self.lam * s)
        osc = np.stack([(self.lam**n * e).imag for n in range(NDER)]) * self.amp
        out[:, m] = product(product(self.rise.stack(t[m]), self.fade.stack(t[m])), osc)
        return out
