"""US Standard Atmosphere 1976 (COESA 1976), −5 km to 1000 km geometric altitude.

Reference: *U.S. Standard Atmosphere, 1976*, NOAA/NASA/USAF, NOAA-S/T 76-1562
(NASA-TM-X-74335). Equation and table numbers below refer to that document.

Model
-----
*0–86 km* (:func:`us76`) — the standard's closed form: geopotential altitude
``H = r0 z / (r0 + z)``, seven layers of constant molecular-scale-temperature gradient
``L_M`` in ``H`` (Table 4), hydrostatic pressure from the barometric formulas (eqs. 33a/b)
and ``rho = p M0 / (R* T_M)``. The kinetic temperature is ``T = T_M (M/M0)``, where the
molecular-weight ratio ``M/M0`` departs from 1 between 80 and 86 km (Table 8, 0.5 km
steps in geometric altitude, interpolated linearly), so that ``T(86 km) = 186.8673 K``.
The first layer is extrapolated down to −5 km; lower altitudes are clamped to −5 km.

*86–1000 km* (:func:`us76_upper`) — the standard's kinetic-temperature profile
(isothermal to 91 km, elliptical 91–110 km, +12 K/km to 120 km, exponential towards
``T_inf = 1000 K`` with ``lambda = 0.01875 /km``; eqs. 23–31) evaluated exactly, and
pressure and density interpolated (linearly in ``ln p``, ``ln rho``) in a table that
:func:`upper_atmosphere_table` builds once by integrating the standard's own equations:
hydrostatic N2 (eq. 33), diffusion with eddy mixing, thermal diffusion and the empirical
vertical-flux terms for O, O2, Ar and He (eqs. 34–37, Table 6), and the flux equation
for atomic hydrogen from 150 km with its boundary value at 500 km (eqs. 38–41), from the
86 km number densities of Table 9. Then ``p = n k T`` and ``rho = sum(n_i M_i) / N_A``.
The integrated table reproduces the published tables to better than 0.04 % in ``p``
and ``rho`` at every 100 km from 100 to 1000 km. The table is shifted by a constant in
``ln p`` and ``ln rho`` (about 2e-6 relative) so that ``p`` and ``rho`` are exactly
continuous with the 0–86 km model at 86 km.

*Speed of sound* — the standard defines ``a = sqrt(gamma R* T_M / M0)`` only up to
86 km. Above, the same formula is continued with the molecular-scale temperature
``T_M = T M0 / M`` of the actual mixture, i.e. ``a = sqrt(gamma p / rho)`` with
``gamma = 1.4`` kept constant. It is continuous at 86 km; above about 150 km (mostly
atomic oxygen, free-molecular flow) it is only a nominal value for forming a Mach number
where the dynamic pressure is negligible anyway. Above 1000 km all outputs are clamped
to their 1000 km values.

Numba interface
---------------
The upper table is not a module global inside compiled code: the caller obtains it once
with :func:`upper_atmosphere_table` and passes the three arrays to :func:`atmosphere`
(or :func:`us76_upper`) on every call. All kernels return the tuple
``(T_K, p_Pa, rho_kgm3, a_mps)`` — kinetic temperature, pressure, mass density and
speed of sound.
"""

from __future__ import annotations

import functools
import math

import numpy as np
from numba import njit

from savant_cli.models import blocks
from savant_cli.models.interp import locate, locate_at, tab, tab_offset

_TABLES = blocks.TABLES.block("atmosphere")
T_ALT = _TABLES.table("atm_alt", "m", "geometric altitudes of the 86–1000 km table")
T_LNP = _TABLES.table("atm_lnp", "ln Pa", "natural log of pressure at T_ALT")
T_LNRHO = _TABLES.table("atm_lnrho", "ln(kg/m^3)", "natural log of density at T_ALT")
_AUX = blocks.DIAGNOSTICS.block("atmosphere")
A_RHO = _AUX.scalar("density", "kg/m^3", "air density (US76)", blocks.Logged("density"))
A_PRES = _AUX.scalar("pressure", "Pa", "static pressure (US76)", blocks.Logged("pressure"))
A_TEMP = _AUX.scalar("temperature", "K", "kinetic temperature (US76)", blocks.Logged("temperature"))
A_SOS = _AUX.scalar("speed_of_sound", "m/s", "speed of sound (US76)", blocks.Logged("speed_of_sound"))


@njit(cache=True, error_model="numpy", inline="always")
def write_diagnostics(aux: np.ndarray, rho: float, pres: float, temp: float, sos: float) -> None:
    """Write the air's density (kg/m³), pressure (Pa), temperature (K) and speed of sound
    (m/s) into ``aux``."""
    aux[A_RHO] = rho
    aux[A_PRES] = pres
    aux[A_TEMP] = temp
    aux[A_SOS] = sos


from savant_cli.constants import G0, GAMMA_AIR, M0, P0, R0_US76, R_STAR, T0

# ------------------------------------------------------------------ lower atmosphere
_R_AIR = R_STAR / M0        # specific gas constant of sea-level air, J/(kg K)
_GMR = G0 * M0 / R_STAR     # hydrostatic constant g0' M0 / R*, K per geopotential m

# Table 4: layer-base geopotential altitudes (m') and molecular-temperature gradients (K/m')
_H_BASE = (0.0, 11000.0, 20000.0, 32000.0, 47000.0, 51000.0, 71000.0, 84852.0)
_LAPSE = (-0.0065, 0.0, 0.0010, 0.0028, 0.0, -0.0028, -0.0020)

# Table 8: M/M0 at geometric altitudes 80, 80.5, ..., 86 km
_M_RATIO = (1.000000, 0.999996, 0.999989, 0.999971, 0.999941, 0.999909, 0.999870,
            0.999829, 0.999786, 0.999741, 0.999694, 0.999641, 0.999579)

Z_MIN = -5000.0             # lowest altitude of the model, m
Z_86 = 86000.0              # junction of the two formulations, m
Z_TOP = 1.0e6               # highest altitude of the model, m


def _layer_bases() -> tuple[tuple[float, ...], tuple[float, ...]]:
    """Molecular-scale temperature (K) and pressure (Pa) at each layer base (eqs. 23, 33)."""
    tm, p = [T0], [P0]
    for b in range(len(_LAPSE)):
        dh = _H_BASE[b + 1] - _H_BASE[b]
        tm.append(tm[b] + _LAPSE[b] * dh)
        if _LAPSE[b] == 0.0:
            p.append(p[b] * math.exp(-_GMR * dh / tm[b]))
        else:
            p.append(p[b] * (tm[b] / tm[b + 1]) ** (_GMR / _LAPSE[b]))
    return tuple(tm), tuple(p)


_TM_BASE, _P_BASE = _layer_bases()   # 8 values each; the last is the 84.852 km' top


@njit(cache=True, error_model="numpy")
def us76(alt_m: float) -> tuple[float, float, float, float]:
    """US76 atmosphere below 86 km from the standard's closed-form equations.

    Parameters
    ----------
    alt_m : float
        Geometric altitude above mean sea level, m. Clamped to [−5 km, 86 km]; the first
        layer is extrapolated below 0 m.

    Returns
    -------
    T_K : float
        Kinetic temperature, K.
    p_Pa : float
        Pressure, Pa.
    rho_kgm3 : float
        Mass density, kg/m^3.
    a_mps : float
        Speed of sound ``sqrt(gamma R* T_M / M0)``, m/s.
    """
    z = min(max(alt_m, Z_MIN), Z_86)
    h = R0_US76 * z / (R0_US76 + z)            # geopotential altitude, m'
    b = 0
    for i in range(1, 7):
        if h >= _H_BASE[i]:
            b = i
    tb = _TM_BASE[b]
    lapse = _LAPSE[b]
    dh = h - _H_BASE[b]
    tm = tb + lapse * dh                        # molecular-scale temperature, K
    if lapse == 0.0:
        p = _P_BASE[b] * np.exp(-_GMR * dh / tb)
    else:
        p = _P_BASE[b] * (tb / tm) ** (_GMR / lapse)
    rho = p / (_R_AIR * tm)
    a = np.sqrt(GAMMA_AIR * _R_AIR * tm)
    t = tm
    if z > 80000.0:                             # kinetic T = T_M M/M0 (Table 8)
        x = (z - 80000.0) / 500.0
        k = min(int(x), 11)
        t = tm * (_M_RATIO[k] + (x - k) * (_M_RATIO[k + 1] - _M_RATIO[k]))
    return t, p, rho, a


# ------------------------------------------------------------------ upper atmosphere
_T7 = 186.8673              # kinetic temperature at 86-91 km, K
_TC, _A_ELL, _B_ELL = 263.1905, -76.3232, -19942.9   # elliptical segment: K, K, m
_T9, _LK9 = 240.0, 0.012    # 110 km temperature (K) and gradient (K/m)
_T10, _T_INF = 360.0, 1000.0
_LAMBDA = 1.875e-5          # 1/m


@njit(cache=True, error_model="numpy")
def upper_temperature(alt_m: float) -> tuple[float, float]:
    """US76 kinetic temperature and its gradient, 86–1000 km (eqs. 25–31).

    Parameters
    ----------
    alt_m : float
        Geometric altitude, m; clamped to [86 km, 1000 km].

    Returns
    -------
    T_K : float
        Kinetic temperature, K.
    dTdz_Kpm : float
        Gradient dT/dz, K/m.
    """
    z = min(max(alt_m, Z_86), Z_TOP)
    if z < 91000.0:
        return _T7, 0.0
    if z < 110000.0:
        x = (z - 91000.0) / _B_ELL
        s = np.sqrt(1.0 - x * x)
        return _TC + _A_ELL * s, -_A_ELL * x / (_B_ELL * s)
    if z < 120000.0:
        return _T9 + _LK9 * (z - 110000.0), _LK9
    c = (R0_US76 + 120000.0) / (R0_US76 + z)
    e = (_T_INF - _T10) * np.exp(-_LAMBDA * (z - 120000.0) * c)
    return _T_INF - e, _LAMBDA * c * c * e


@njit(cache=True, error_model="numpy")
def us76_upper(alt_m: float, table_alt_m: np.ndarray, table_lnp: np.ndarray,
               table_lnrho: np.ndarray) -> tuple[float, float, float, float]:
    """US76 atmosphere from 86 to 1000 km (table from :func:`upper_atmosphere_table`).

    Parameters
    ----------
    alt_m : float
        Geometric altitude, m; clamped to [86 km, 1000 km].
    table_alt_m, table_lnp, table_lnrho : ndarray
        Altitude grid (m), ``ln(p / 1 Pa)`` and ``ln(rho / 1 kg m^-3)``.

    Returns
    -------
    T_K, p_Pa, rho_kgm3, a_mps : float
        Kinetic temperature (K), pressure (Pa), density (kg/m^3) and the continued
        speed of sound ``sqrt(gamma p / rho)`` (m/s).
    """
    z = min(max(alt_m, Z_86), Z_TOP)
    i, w = locate(table_alt_m, table_alt_m.size, z)
    return _upper_cell(z, w, table_lnp[i], table_lnp[i + 1], table_lnrho[i], table_lnrho[i + 1])


@njit(cache=True, error_model="numpy")
def _upper_cell(z: float, w: float, lnp0: float, lnp1: float, lnr0: float, lnr1: float):
    """Temperature, pressure, density and speed of sound from one table cell (log-linear)."""
    t = upper_temperature(z)[0]
    p = np.exp((1.0 - w) * lnp0 + w * lnp1)
    rho = np.exp((1.0 - w) * lnr0 + w * lnr1)
    return t, p, rho, np.sqrt(GAMMA_AIR * p / rho)


@njit(cache=True, error_model="numpy")
def atmosphere_at(alt_m: float, a: np.ndarray, off_alt: int, off_lnp: int, off_lnrho: int,
                  n: int) -> tuple[float, float, float, float]:
    """:func:`atmosphere` with the upper table held in one flat array ``a`` at the given
    offsets (``n`` rows), as the compiled plant stores it."""
    if alt_m < Z_86:
        return us76(alt_m)
    z = min(max(alt_m, Z_86), Z_TOP)
    i, w = locate_at(a, off_alt, n, z)
    return _upper_cell(z, w, a[off_lnp + i], a[off_lnp + i + 1], a[off_lnrho + i], a[off_lnrho + i + 1])


@njit(cache=True, error_model="numpy")
def atmosphere(alt_m: float, upper_alt_m: np.ndarray, upper_lnp: np.ndarray,
               upper_lnrho: np.ndarray) -> tuple[float, float, float, float]:
    """US76 atmosphere, −5 km to 1000 km geometric altitude (clamped outside).

    Parameters
    ----------
    alt_m : float
        Geometric altitude, m (the simulation uses the WGS84 geodetic height).
    upper_alt_m, upper_lnp, upper_lnrho : ndarray
        The arrays returned by :func:`upper_atmosphere_table`.

    Returns
    -------
    T_K, p_Pa, rho_kgm3, a_mps : float
        Kinetic temperature (K), pressure (Pa), density (kg/m^3), speed of sound (m/s).
    """
    if alt_m < Z_86:
        return us76(alt_m)
    return us76_upper(alt_m, upper_alt_m, upper_lnp, upper_lnrho)


# ------------------------------------------------ upper table: the standard's equations
_K_BOLTZ = 1.380622e-23     # Boltzmann constant (US76 value), J/K
_N_AVO = 6.022169e26        # Avogadro constant (US76 value), 1/kmol
_RS = 1000.0 * R_STAR       # gas constant, J/(kmol K)
_M0K = 1000.0 * M0          # kg/kmol
# species N2, O, O2, Ar, He: molecular weight (kg/kmol), thermal-diffusion coefficient,
# molecular-diffusion a_i (1/(m s)), b_i, flux-term Q_i (1/m^3), U_i (m), W_i (1/m^3)
_MW = np.array([28.0134, 15.9994, 31.9988, 39.948, 4.0026])
_ALPHA = np.array([0.0, 0.0, 0.0, 0.0, -0.40])
_A_DIFF = np.array([0.0, 6.986e20, 4.863e20, 4.487e20, 1.700e21])
_B_DIFF = np.array([0.0, 0.750, 0.750, 0.870, 0.691])
_Q_FLUX = np.array([0.0, -5.809644e-13, 1.366212e-13, 9.434079e-14, -2.457369e-13])
_U_FLUX = np.array([0.0, 56903.11, 86000.0, 86000.0, 86000.0])
_W_FLUX = np.array([0.0, 2.706240e-14, 8.333333e-14, 8.333333e-14, 6.666667e-13])
_QO, _UO, _WO = -3.416248e-12, 97000.0, 5.008765e-13      # second O flux term (Z < 97 km)
_N86 = np.array([1.129794e20, 8.6e16, 3.030898e19, 1.3514e18, 7.58173e14])  # Table 9, 1/m^3
# atomic hydrogen: molecular weight, alpha, a, b, flux (1/(m^2 s)), density at 500 km (1/m^3)
_MW_H, _ALPHA_H, _A_H, _B_H, _PHI_H, _NH500 = 1.00797, -0.25, 3.305e21, 0.500, 7.2e11, 8.0e10


def _eddy(z: float) -> float:
    """Eddy-diffusion coefficient K (eq. 7), m^2/s."""
    if z < 95000.0:
        return 120.0
    if z < 115000.0:
        return 120.0 * math.exp(1.0 - 4.0e8 / (4.0e8 - (z - 95000.0) ** 2))
    return 0.0


def _species_rhs(z: float, y: np.ndarray) -> np.ndarray:
    """d(ln n_i)/dz for N2, O, O2, Ar, He (eqs. 33-37), 1/m."""
    n = np.exp(y)
    t, dt = upper_temperature(z)
    g = G0 * (R0_US76 / (R0_US76 + z)) ** 2
    k_eddy = _eddy(z)
    below_100 = z < 100000.0
    out = np.empty(5)
    out[0] = -dt / t - (_M0K if below_100 else _MW[0]) * g / (_RS * t)   # N2: mixed/hydrostatic
    for i in range(1, 5):
        # the standard's mixture for D_i and M: N2 alone for O, O2; N2+O+O2 for Ar, He
        m = 1 if i < 3 else 3
        n_mix = n[:m].sum()
        m_mix = _M0K if below_100 else float(n[:m] @ _MW[:m]) / n_mix
        d = _A_DIFF[i] * (t / 273.15) ** _B_DIFF[i] / n_mix
        f = (g / (_RS * t)) * d / (d + k_eddy) * (
            _MW[i] + m_mix * k_eddy / d + _ALPHA[i] * _RS * dt / g)
        dz = z - _U_FLUX[i]
        f += _Q_FLUX[i] * dz * dz * math.exp(-_W_FLUX[i] * dz ** 3)
        if i == 1 and z < _UO:
            dz = _UO - z
            f += _QO * dz * dz * math.exp(-_WO * dz ** 3)
        out[i] = -dt / t - f
    return out


@functools.lru_cache(maxsize=1)
def _upper_table_cached() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    from scipy.integrate import cumulative_trapezoid, solve_ivp

    # grid: 0.25 km to 200 km (includes the 91/100/110/115/120 km kinks), 1 km above
    alt = np.unique(np.concatenate([np.arange(86.0e3, 200.0e3, 250.0),
                                    np.arange(200.0e3, Z_TOP + 1.0, 1000.0)]))
    # species N2..He: integrate ln n piecewise between the discontinuities of the RHS
    breaks = [86.0e3, 91.0e3, 95.0e3, 100.0e3, 110.0e3, 115.0e3, 120.0e3, Z_TOP]
    sols = []
    y0 = np.log(_N86)
    for za, zb in zip(breaks[:-1], breaks[1:]):
        sol = solve_ivp(_species_rhs, (za, zb), y0, method="DOP853", rtol=1e-10,
                        atol=1e-10, dense_output=True)
        sols.append(sol)
        y0 = sol.y[:, -1]

    def number_densities(zz: np.ndarray) -> np.ndarray:
        out = np.empty((zz.size, 5))
        seg = np.clip(np.searchsorted(breaks, zz, side="right") - 1, 0, len(sols) - 1)
        for s, sol in enumerate(sols):
            sel = seg == s
            if sel.any():
                out[sel] = np.exp(sol.sol(zz[sel]).T)
        return out

    def temperature(zz: np.ndarray) -> np.ndarray:
        return np.array([upper_temperature(v)[0] for v in zz])

    # atomic hydrogen, 150-1000 km (eqs. 38-41): with tau(z) = int_500^z g M_H/(R* T) dz,
    # n_H = [n_H(500) - int_500^z phi/D_H (T/T500)^(1+a) e^tau dz] (T500/T)^(1+a) e^-tau
    zh = np.arange(150.0e3, Z_TOP + 1.0, 100.0)
    th = temperature(zh)
    gh = G0 * (R0_US76 / (R0_US76 + zh)) ** 2
    i500 = int(np.argmin(np.abs(zh - 500.0e3)))
    tau = cumulative_trapezoid(gh * _MW_H / (_RS * th), zh, initial=0.0)
    tau -= tau[i500]
    d_h = _A_H * (th / 273.15) ** _B_H / number_densities(zh).sum(axis=1)
    ratio = th / th[i500]
    integral = cumulative_trapezoid(_PHI_H / d_h * ratio ** (1.0 + _ALPHA_H) * np.exp(tau),
                                    zh, initial=0.0)
    integral -= integral[i500]
    n_h = (_NH500 - integral) * ratio ** -(1.0 + _ALPHA_H) * np.exp(-tau)

    n = number_densities(alt)
    nh = np.where(alt >= 150.0e3, np.interp(alt, zh, n_h), 0.0)
    t = temperature(alt)
    lnp = np.log((n.sum(axis=1) + nh) * _K_BOLTZ * t)
    lnrho = np.log((n @ _MW + nh * _MW_H) / _N_AVO)
    # exact continuity with the closed-form 0-86 km model
    _, p86, rho86, _ = us76(Z_86)
    lnp += math.log(p86) - lnp[0]
    lnrho += math.log(rho86) - lnrho[0]
    for arr in (alt, lnp, lnrho):
        arr.setflags(write=False)
    return alt, lnp, lnrho


def upper_atmosphere_table() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Table of the US76 upper atmosphere, 86–1000 km, for :func:`atmosphere`.

    Built on the first call (about 0.2 s) by integrating the standard's diffusion
    equations (see the module docstring) and cached; each call returns fresh copies.

    Returns
    -------
    alt_m : ndarray
        Geometric altitudes, m, increasing from 86 000 to 1 000 000 (0.25 km steps to
        200 km, 1 km above).
    lnp : ndarray
        Natural log of pressure in Pa.
    lnrho : ndarray
        Natural log of mass density in kg/m^3.

    All three are contiguous float64 arrays of the same length.
    """
    return tuple(np.ascontiguousarray(a, dtype=np.float64).copy()
                 for a in _upper_table_cached())


@njit(cache=True, error_model="numpy")
def _profile(alt_m: np.ndarray, upper_alt_m: np.ndarray, upper_lnp: np.ndarray,
             upper_lnrho: np.ndarray) -> np.ndarray:
    out = np.empty((alt_m.size, 4))
    for i in range(alt_m.size):
        t, p, rho, a = atmosphere(alt_m[i], upper_alt_m, upper_lnp, upper_lnrho)
        out[i, 0] = t
        out[i, 1] = p
        out[i, 2] = rho
        out[i, 3] = a
    return out


def us76_profile(alt_m: np.ndarray) -> dict[str, np.ndarray]:
    """Vectorised US76 atmosphere for plots and tests.

    Parameters
    ----------
    alt_m : array_like
        Geometric altitudes, m (any shape).

    Returns
    -------
    dict
        ``alt_m`` (m), ``T_K`` (K), ``p_Pa`` (Pa), ``rho_kgm3`` (kg/m^3) and ``a_mps``
        (m/s), each an array of the input's shape.
    """
    z = np.asarray(alt_m, dtype=np.float64)
    res = _profile(np.ascontiguousarray(z.ravel()), *upper_atmosphere_table())
    shape = z.shape
    return {"alt_m": z.copy(), "T_K": res[:, 0].reshape(shape), "p_Pa": res[:, 1].reshape(shape),
            "rho_kgm3": res[:, 2].reshape(shape), "a_mps": res[:, 3].reshape(shape)}


def build(inputs: blocks.ModelInputs, p: np.ndarray, tables: dict[str, np.ndarray]) -> None:
    """The integrated upper-atmosphere table (built once per process)."""
    alt, lnp, lnrho = upper_atmosphere_table()
    tables.update(atm_alt=alt, atm_lnp=lnp, atm_lnrho=lnrho)


@njit(cache=True, error_model="numpy", inline="always")
def air_at(alt_m: float, tb: np.ndarray) -> tuple[float, float, float, float]:
    """US76 ``(T K, p Pa, ρ kg/m³, a m/s)`` at a geometric altitude, from the packed tables."""
    o_atm, n_atm = tab(tb, T_ALT)
    return atmosphere_at(alt_m, tb, o_atm, tab_offset(tb, T_LNP), tab_offset(tb, T_LNRHO), n_atm)


@njit(cache=True, error_model="numpy")
def air_at_packed(alt_m: float, tb: np.ndarray) -> tuple[float, float, float, float]:
    """:func:`air_at` for Python callers (the data generators)."""
    return air_at(alt_m, tb)
