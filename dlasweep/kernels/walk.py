"""Exact random-walk moves shared by every model.

Uniform directions, walk-on-spheres jumps, and the exact return of a walker
from outside the launch circle/sphere or above the launch line/plane; their
laws under a drift (``drift_dir``, ``drift_to_plane``); and the
kernels' hot-loop random stream, a xoshiro256+ generator seeded from the
numpy Generator (numpy's Generator costs several times more per draw from
numba).

Throughout, ``dim`` is the dimension (2 or 3); ``s0``, ``s1``, ``s2``, ``s3``
(uint64) are a xoshiro256+ state held in registers, passed in and returned
(``xo``); ``rs`` (uint64 (4,)) is the same state in an array
(``seed_stream``); ``rng`` is the numpy Generator.
"""

import numpy as np

from .._jit import borrow, inline, jit


@jit
def seed_stream(rng):
    """A xoshiro256+ state (uint64 (4,)) drawn from the Generator ``rng`` (splitmix64 expanded)."""
    rs = np.zeros(4, np.uint64)
    z = np.uint64(rng.integers(1, 2**62))
    for k in range(4):
        z += np.uint64(0x9E3779B97F4A7C15)
        x = z
        x = (x ^ (x >> np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)
        x = (x ^ (x >> np.uint64(27))) * np.uint64(0x94D049BB133111EB)
        rs[k] = x ^ (x >> np.uint64(31))
    return rs


@inline
def xo(s0, s1, s2, s3):
    """xoshiro256+ step on a state kept in registers: new state and a double in [0, 1).

    Parameters
    ----------
    s0, s1, s2, s3 : uint64
        The generator's state, passed as scalars so that a hot loop keeps it in registers.

    Returns
    -------
    tuple
        The next state ``s0, s1, s2, s3`` and the double drawn.
    """
    r = np.float64((s0 + s3) >> np.uint64(11)) * (1.0 / 9007199254740992.0)
    t = s1 << np.uint64(17)
    s2 ^= s0
    s3 ^= s1
    s1 ^= s2
    s0 ^= s3
    s2 ^= t
    s3 = (s3 << np.uint64(45)) | (s3 >> np.uint64(19))
    return s0, s1, s2, s3, r


@inline
def xdir(s0, s1, s2, s3, dim):
    """Uniform unit vector by rejection from the unit disk (2D: normalise;
    3D: Marsaglia's map), without sin/cos; the state in registers.

    Parameters
    ----------
    s0, s1, s2, s3 : uint64
        The stream's state (``xo``).
    dim : int
        The dimension, 2 or 3.

    Returns
    -------
    tuple
        The next state ``s0, s1, s2, s3`` and the vector's three components (the third 0 in 2D).
    """
    while True:
        s0, s1, s2, s3, a = xo(s0, s1, s2, s3)
        s0, s1, s2, s3, b = xo(s0, s1, s2, s3)
        x = 2.0 * a - 1.0
        y = 2.0 * b - 1.0
        q = x * x + y * y
        if 0.0 < q < 1.0:
            break
    if dim == 2:
        inv = 1.0 / np.sqrt(q)
        return s0, s1, s2, s3, x * inv, y * inv, 0.0
    f = 2.0 * np.sqrt(1.0 - q)
    return s0, s1, s2, s3, x * f, y * f, 1.0 - 2.0 * q


@jit
def uniform(rs):
    """A double in [0, 1) from the stream state ``rs`` (``seed_stream``)."""
    rs[0], rs[1], rs[2], rs[3], r = xo(rs[0], rs[1], rs[2], rs[3])
    return r


@jit
def unit_vector(rs, dim, out):
    """A uniform unit vector into ``out[:3]`` from the stream state ``rs``.

    ``dim`` is the dimension, 2 or 3 (``out[2]`` is 0 in 2D).
    """
    rs[0], rs[1], rs[2], rs[3], out[0], out[1], out[2] = xdir(rs[0], rs[1], rs[2], rs[3], dim)


@jit
def below(rng, m):
    """A uniform integer in [0, m); far cheaper in numba than ``rng.integers``."""
    return np.int64(rng.random() * m)


@jit
def direction(rng, dim, out):
    """Fill ``out[:dim]`` with a uniform random unit vector.

    Rejection from the unit disk (Marsaglia's method in 3D) avoids the
    trigonometric calls, which cost more than the extra draws.

    ``rng`` is the numpy Generator drawn from; ``dim`` is the dimension, 2 or 3.
    """
    while True:
        u = 2.0 * rng.random() - 1.0
        v = 2.0 * rng.random() - 1.0
        s = u * u + v * v
        if 0.0 < s < 1.0:
            break
    if dim == 2:
        out[0] = (u * u - v * v) / s
        out[1] = 2.0 * u * v / s
        out[2] = 0.0
        return
    f = 2.0 * np.sqrt(1.0 - s)
    out[0] = u * f
    out[1] = v * f
    out[2] = 1.0 - 2.0 * s


@inline
def _moebius(u0, u1, rho):
    """The point of the unit circle where Brownian motion from ``rho`` (on the real axis,
    ``|rho| < 1``) leaves the unit disk, from the uniform point ``u`` = (u0, u1): the Moebius map
    z -> (z + rho) / (1 + rho z) takes the uniform law on the circle to the Poisson kernel
    seen from rho; no trigonometry."""
    zr, zi = u0 + rho, u1
    dr, di = 1.0 + rho * u0, rho * u1
    den = dr * dr + di * di
    return (zr * dr + zi * di) / den, (zi * dr - zr * di) / den


@inline
def _poisson_cos(radius, inner, x):
    """The cosine of the angle, seen from the centre and counted from the point's own
    direction, at which Brownian motion from a point ``inner`` from the centre of a sphere of
    ``radius`` leaves the ball (3D, ``inner < radius``): its inverse distance to the exit point
    is uniform (``x`` a uniform draw)."""
    lo, hi = 1.0 / (radius + inner), 1.0 / (radius - inner)
    inv = hi - x * (hi - lo)
    cos_t = (radius * radius + inner * inner - 1.0 / (inv * inv)) / (2.0 * inner * radius)
    return min(1.0, max(-1.0, cos_t))


@inline
def _about_axis(a0, a1, a2, cos_t, c, s):
    """The unit vector at angle acos(cos_t) from the unit axis a = (a0, a1, a2), turned about it by the
    angle whose cosine and sine are ``c`` and ``s``."""
    if abs(a0) < 0.9:
        e0, e1, e2 = 0.0, a2, -a1
    else:
        e0, e1, e2 = -a2, 0.0, a0
    n1 = np.sqrt(e0 * e0 + e1 * e1 + e2 * e2)
    e0, e1, e2 = e0 / n1, e1 / n1, e2 / n1
    f0, f1, f2 = a1 * e2 - a2 * e1, a2 * e0 - a0 * e2, a0 * e1 - a1 * e0
    sin_t = np.sqrt(1.0 - cos_t * cos_t)
    c, s = sin_t * c, sin_t * s
    return cos_t * a0 + c * e0 + s * f0, cos_t * a1 + c * e1 + s * f1, cos_t * a2 + c * e2 + s * f2


@borrow
def return_to_sphere(rng, dim, pos, radius, scratch):
    """Move a walker at ``|pos| > radius`` to where it first hits the sphere (``scratch``:
    float64 (3,) of working space; ``pos`` float64 (3,), moved).

    2D: the exterior Poisson kernel is a wrapped Cauchy law in the angle with
    concentration ``radius / |pos|``; the walker always returns.
    3D: it escapes to infinity with probability ``1 - radius/|pos|`` (returns
    False); otherwise the hitting point follows the Kelvin image of the
    interior Poisson kernel from the inverted point ``radius**2 / |pos|``.
    Returns True when the walker was placed on the sphere.

    ``rng`` is the numpy Generator drawn from; ``dim`` is the dimension, 2 or 3.
    """
    r = np.sqrt(pos[0] ** 2 + pos[1] ** 2 + pos[2] ** 2)
    if dim == 2:
        direction(rng, 2, scratch)
        wr, wi = _moebius(scratch[0], scratch[1], radius / r)
        er, ei = pos[0] / r, pos[1] / r
        pos[0] = radius * (wr * er - wi * ei)
        pos[1] = radius * (wr * ei + wi * er)
        return True
    if rng.random() >= radius / r:
        return False
    cos_t = _poisson_cos(radius, radius * radius / r, rng.random())  # the Kelvin image's distance from the centre
    phi = 2.0 * np.pi * rng.random()
    v0, v1, v2 = _about_axis(pos[0] / r, pos[1] / r, pos[2] / r, cos_t, np.cos(phi), np.sin(phi))
    pos[0] = radius * v0
    pos[1] = radius * v1
    pos[2] = radius * v2
    return True


@borrow
def ball_exit(s0, s1, s2, s3, dim, w, c0, c1, c2, radius):
    """Move the walker at w (float64 (3,)), inside the ball of ``radius`` about c = (c0, c1, c2), to
    where Brownian motion
    from it first leaves the ball (the interior Poisson kernel, as ``return_to_sphere`` draws
    it), from the stream state in registers (see ``xdir``), which it returns.

    An exact jump where the ball about w that walk-on-spheres would take is smaller: the
    same law as walk-on-spheres inside the larger ball, in one draw.

    Parameters
    ----------
    s0, s1, s2, s3 : uint64
        The stream's state (``xo``).
    dim : int
        The dimension, 2 or 3.
    w : float64 (3,)
        The walker's position, moved in place.
    c0, c1, c2 : float
        The ball's centre.
    radius : float
        The ball's radius.
    """
    d0, d1, d2 = w[0] - c0, w[1] - c1, w[2] - c2
    inner = np.sqrt(d0 * d0 + d1 * d1 + d2 * d2)
    if inner <= 1e-9 * radius:  # at the centre: a uniform point
        s0, s1, s2, s3, u0, u1, u2 = xdir(s0, s1, s2, s3, dim)
        w[0], w[1], w[2] = c0 + radius * u0, c1 + radius * u1, c2 + radius * u2
        return s0, s1, s2, s3
    a0, a1, a2 = d0 / inner, d1 / inner, d2 / inner
    if dim == 2:
        s0, s1, s2, s3, u0, u1, _ = xdir(s0, s1, s2, s3, 2)
        wr, wi = _moebius(u0, u1, inner / radius)
        w[0] = c0 + radius * (wr * a0 - wi * a1)
        w[1] = c1 + radius * (wr * a1 + wi * a0)
        return s0, s1, s2, s3
    s0, s1, s2, s3, x = xo(s0, s1, s2, s3)
    s0, s1, s2, s3, c, s, _ = xdir(s0, s1, s2, s3, 2)  # a uniform angle about the axis
    v0, v1, v2 = _about_axis(a0, a1, a2, _poisson_cos(radius, inner, x), c, s)
    w[0] = c0 + radius * v0
    w[1] = c1 + radius * v1
    w[2] = c2 + radius * v2
    return s0, s1, s2, s3


@borrow
def return_to_plane(rng, dim, pos, height, width):
    """Move a walker at ``pos`` (float64 (3,)) above ``height`` (last axis up) to where it first hits it.

    The half-space Poisson kernel: a Cauchy offset (2D) or its radial
    analogue (3D) with scale ``pos_up - height``; the periodic sides of width
    ``width`` wrap it, which gives the strip's exact kernel.

    ``rng`` is the numpy Generator drawn from; ``dim`` is the dimension, 2 or 3.
    """
    up = dim - 1
    h = pos[up] - height
    if dim == 2:
        pos[0] = (pos[0] + h * np.tan(np.pi * (rng.random() - 0.5))) % width
    else:
        u = rng.random()
        rad = h * np.sqrt(1.0 / ((1.0 - u) * (1.0 - u)) - 1.0)
        a = 2.0 * np.pi * rng.random()
        pos[0] = (pos[0] + rad * np.cos(a)) % width
        pos[1] = (pos[1] + rad * np.sin(a)) % width
    pos[up] = height


@inline
def drift_dir(s0, s1, s2, s3, dim, kappa, a0, a1, a2):
    """Where Brownian motion with drift leaves a ball from its centre, as a unit vector: the density
    on the sphere is proportional to exp(kappa a.x), a von Mises (2D) or von Mises-Fisher (3D) law.

    By Girsanov's theorem the drift reweights a driftless path by exp(mu.x - |mu|**2 D t) at its
    exit point x and time t; from the centre, x and t are independent without drift (rotational
    symmetry), so the exit point's law is the uniform one tilted by exp(mu.x), whatever the time:
    ``kappa`` is |mu| times the radius. 2D draws Best and Fisher's rejection (1979; its constants
    written without the cancellation of their usual form at small kappa, its uniform angle's cosine
    and sign from ``xdir``); 3D the inverse of the law of w = a.x, w = 1 + log(1 - x (1 - exp(-2
    kappa))) / kappa (``log1p``, ``expm1``: no cancellation at small kappa), and a uniform angle about a.
    At kappa 0 it is ``xdir``.

    Parameters
    ----------
    s0, s1, s2, s3 : uint64
        The stream's state (``xo``).
    dim : int
        The dimension, 2 or 3.
    kappa : float
        The concentration, >= 0: the drift (v / (2 D)) times the radius.
    a0, a1, a2 : float
        The drift's unit direction (a2 0 in 2D).

    Returns
    -------
    tuple
        The next state ``s0, s1, s2, s3`` and the vector's three components (the third 0 in 2D).
    """
    if kappa <= 0.0:
        return xdir(s0, s1, s2, s3, dim)
    if dim == 2:
        tau = 1.0 + np.sqrt(1.0 + 4.0 * kappa * kappa)
        rho = 2.0 * kappa / (tau + np.sqrt(2.0 * tau))
        r = (1.0 + rho * rho) / (2.0 * rho)
        while True:
            s0, s1, s2, s3, z, side, _ = xdir(s0, s1, s2, s3, 2)
            f = (1.0 + r * z) / (r + z)
            c = kappa * (r - f)
            s0, s1, s2, s3, x = xo(s0, s1, s2, s3)
            if c * (2.0 - c) > x or np.log(c / x) + 1.0 - c >= 0.0:
                break
        f = min(1.0, max(-1.0, f))
        t = np.sqrt(1.0 - f * f) if side >= 0.0 else -np.sqrt(1.0 - f * f)
        return s0, s1, s2, s3, f * a0 - t * a1, f * a1 + t * a0, 0.0
    s0, s1, s2, s3, x = xo(s0, s1, s2, s3)
    w = min(1.0, max(-1.0, 1.0 + np.log1p(x * np.expm1(-2.0 * kappa)) / kappa))
    s0, s1, s2, s3, c, s, _ = xdir(s0, s1, s2, s3, 2)  # a uniform angle about the axis
    v0, v1, v2 = _about_axis(a0, a1, a2, w, c, s)
    return s0, s1, s2, s3, v0, v1, v2


@jit
def inverse_gaussian(rng, mean, shape):
    """A draw of the inverse Gaussian law of ``mean`` and ``shape`` (Michael, Schucany and Haas 1976),
    its root written as 1 / (1 + t + sqrt(t (t + 2))), without the cancellation of the usual form
    when the drift is large; ``rng`` the numpy Generator."""
    y = rng.standard_normal() ** 2
    t = mean * y / (2.0 * shape)
    x = mean / (1.0 + t + np.sqrt(t * (t + 2.0)))
    return x if rng.random() * (mean + x) <= mean else mean * mean / x


@borrow
def drift_to_plane(rng, dim, pos, height, width, mu0, mu1, mu2):
    """``return_to_plane`` under the drift mu = (mu0, mu1, mu2) (v / (2 D), its last axis's component
    <= 0: towards the plane): where the walker at ``pos`` above ``height`` first hits it.

    In the time unit where D is 1/2 the velocity is mu: the hitting time of the plane from height h is
    inverse Gaussian of mean h / |mu_up| and shape h**2 (Levy's law h**2 / N**2 when mu_up is 0), and
    each lateral axis moves by mu_a t plus a Gaussian of variance t, independent of the vertical
    path; the periodic sides of width ``width`` wrap it. Exact.

    Parameters
    ----------
    rng : numpy.random.Generator
        Draws the time and the offsets.
    dim : int
        The dimension, 2 or 3.
    pos : float64 (3,)
        The walker's position, moved in place.
    height : float
        The plane's height (last axis).
    width : float
        The sides' period.
    mu0, mu1, mu2 : float
        The drift vector; mu1 (2D) or mu2 (3D) is the vertical component.
    """
    up = dim - 1
    h = pos[up] - height
    down = -(mu1 if dim == 2 else mu2)
    if down > 0.0:
        t = inverse_gaussian(rng, h / down, h * h)
    else:
        t = h * h / rng.standard_normal() ** 2
    pos[0] = (pos[0] + mu0 * t + np.sqrt(t) * rng.standard_normal()) % width
    if dim == 3:
        pos[1] = (pos[1] + mu1 * t + np.sqrt(t) * rng.standard_normal()) % width
    pos[up] = height
