"""The analytic empirical-inverse wear estimator of thesis 4.4.

Two vibration features are modelled as cubics in the cycle count, ``x_pp(n)`` and ``K(n)`` with
``n = N / 1e6``, and the pinion root wear as the empirical law of 4.1,
``h(N) = a1 exp(a2 N) + a3 exp(a4 N)``. For a measured pair ``(x_pp, K)`` the estimator finds the
cycle count ``N`` in ``[0, N_max]`` that both cubics agree on, and returns ``h(N)``. Each cubic
alone is not monotone (kurtosis first falls, then rises), so one feature can have two or three
roots; the second feature picks the consistent one. In practice we minimise the sum of the two
squared residuals, each scaled by its tolerance, over a fine grid in ``N`` refined by a parabola,
and flag a pair whose residuals exceed the tolerances (no consistent root) or that lies outside
the range the cubics cover on ``[0, N_max]`` (no silent extrapolation).

``EmpiricalInverse.fit`` builds the estimator from physics data of any case;
``EmpiricalInverse.from_config`` takes published coefficients
(``conf/physics/estimator/thesis.yaml``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from physics.params import config_choices, config_file


@dataclass(frozen=True)
class Estimate:
    """Estimated wear and cycles per input row, with the flags that qualify them."""

    wear: np.ndarray  # pinion root wear, in the unit of the wear law
    cycles: np.ndarray  # N
    consistent: np.ndarray  # both features agree on N within their tolerances
    in_range: np.ndarray  # both features lie inside what the cubics span on [0, N_max]

    @property
    def valid(self) -> np.ndarray:
        return self.consistent & self.in_range


@dataclass(frozen=True)
class EmpiricalInverse:
    """Cubic feature models, the wear law, and the tolerances of the consistency check."""

    p2p_cubic: np.ndarray  # highest power first, in n = N / cycles_unit
    kurtosis_cubic: np.ndarray
    wear_law: np.ndarray  # a1, a2, a3, a4 (N in cycles)
    cycles_max: float
    cycles_unit: float = 1e6
    p2p_tol: float = 0.0  # residual allowed before a pair is called inconsistent
    kurtosis_tol: float = 0.0

    # -- construction ----------------------------------------------------------------------
    @classmethod
    def fit(cls, cycles: np.ndarray, p2p: np.ndarray, kurtosis: np.ndarray, wear: np.ndarray,
            tolerance_sigmas: float = 3.0) -> EmpiricalInverse:
        """Fit the cubics and the wear law to physics data (one row per wear state).

        The tolerances are ``tolerance_sigmas`` times each cubic's RMS residual (with a floor of
        1e-6 of the feature's span, for noiseless data).
        """
        cycles, p2p, kurtosis, wear = (np.asarray(a, float) for a in (cycles, p2p, kurtosis,
                                                                        wear))
        if not (cycles.shape == p2p.shape == kurtosis.shape == wear.shape) or cycles.size < 6:
            raise ValueError("cycles, p2p, kurtosis and wear need the same length, at least 6")
        n = cycles / 1e6
        pc, kc = np.polyfit(n, p2p, 3), np.polyfit(n, kurtosis, 3)
        law = _fit_law(cycles, wear)

        def tol(c, y):
            rms = float(np.sqrt(np.mean((np.polyval(c, n) - y) ** 2)))
            return max(tolerance_sigmas * rms, 1e-6 * float(np.ptp(y)) + 1e-300)

        return cls(pc, kc, law, float(cycles.max()), 1e6, tol(pc, p2p), tol(kc, kurtosis))

    @classmethod
    def from_config(cls, name: str = "thesis", tolerance_pct: float = 5.0) -> EmpiricalInverse:
        """Published coefficients from ``conf/physics/estimator/<name>.yaml`` (p2p in metres).

        Without fit residuals the tolerances are ``tolerance_pct`` of each cubic's span over
        ``[0, cycles_max]``.

        Parameters
        ----------
        name : str
            A file of ``conf/physics/estimator`` (``"thesis"``: the case-3 models of thesis 4.1
            and 4.4, Table 13).
        tolerance_pct : float
            Tolerance of the consistency check, in percent of each cubic's span.

        Returns
        -------
        EmpiricalInverse
            The estimator; its wear is in the unit of the wear law (mm for ``"thesis"``).

        Raises
        ------
        ValueError
            For a ``name`` with no file in ``conf/physics/estimator``.

        Examples
        --------
        The thesis's case-3 models (Table 13), peak-to-peak in metres, wear in mm; the wear law
        ``h(N) = a1 exp(a2 N) + a3 exp(a4 N)`` gives 5.3 um at 1e7 cycles, where Table 14 lists
        5.317 um:

        >>> est = EmpiricalInverse.from_config("thesis")
        >>> est.cycles_max, est.cycles_unit
        (15000000.0, 1000000.0)
        >>> f"{est.p2p_cubic[-1]:.4g}"  # x_pp(0) [m]: Table 14's first row, 2.548e-5 m
        '2.548e-05'
        >>> round(float(est.wear_at(1e7)) * 1e3, 1)  # [um]
        5.3
        """
        import yaml

        known = config_choices("estimator")
        if name not in known:
            raise ValueError(f"estimator {name!r} is not in conf/physics/estimator; choose from "
                             f"{known}")
        path = config_file("estimator", f"{name}.yaml")
        c = yaml.safe_load(path.read_text())
        pc = np.asarray(c["p2p_cubic"], float) * float(c["p2p_unit_m"])
        kc = np.asarray(c["kurtosis_cubic"], float)
        est = cls(pc, kc, np.asarray(c["wear_law_mm"], float), float(c["cycles_max"]),
                  float(c["cycles_unit"]))
        span_p, span_k = (np.ptp(np.polyval(cc, est._grid() / est.cycles_unit)) for cc in (pc, kc))
        return cls(pc, kc, est.wear_law, est.cycles_max, est.cycles_unit,
                   tolerance_pct / 100 * span_p, tolerance_pct / 100 * span_k)

    # -- use --------------------------------------------------------------------------------
    def wear_at(self, cycles: np.ndarray) -> np.ndarray:
        a1, a2, a3, a4 = self.wear_law
        cycles = np.asarray(cycles, float)
        return a1 * np.exp(a2 * cycles) + a3 * np.exp(a4 * cycles)

    def _grid(self) -> np.ndarray:
        return np.linspace(0.0, self.cycles_max, 3001)

    def predict(self, p2p: np.ndarray, kurtosis: np.ndarray, chunk: int = 4096) -> Estimate:
        """Estimate N and wear for each (peak-to-peak, kurtosis) pair (vectorised in chunks).

        The cycle count minimises the sum of the two squared residuals of the cubics, each over
        its tolerance, on a grid of ``[0, cycles_max]`` refined by a parabola; the wear is the
        wear law at that count (thesis 4.4; module docstring).

        Parameters
        ----------
        p2p : array_like
            Peak-to-peak of the DTE records [m] (broadcast against ``kurtosis``).
        kurtosis : array_like
            Pearson kurtosis of the same records (normal = 3).
        chunk : int
            Rows evaluated at once (memory: ``chunk`` x 3001 grid points).

        Returns
        -------
        Estimate
            Wear (in the unit of the wear law) and cycles per row, with the flags ``consistent``
            (both features agree on the cycle count) and ``in_range`` (both lie in what the
            cubics span).

        Raises
        ------
        ValueError
            For NaN or infinite features, or an estimator without tolerances (built neither by
            :meth:`fit` nor by :meth:`from_config`).

        Examples
        --------
        Two rows of thesis Table 14 (case 3, DTE features), read back by the thesis's own
        models: at 8e6 cycles (x_pp 2.922e-5 m, K 2.461; wear 3.789 um) and at 1.2e7 cycles
        (4.610e-5 m, 3.346; 7.332 um):

        >>> est = EmpiricalInverse.from_config("thesis")
        >>> out = est.predict(np.array([2.922e-5, 4.610e-5]), np.array([2.461, 3.346]))
        >>> [round(float(n) / 1e6, 1) for n in out.cycles]  # [1e6 cycles]
        [8.0, 11.9]
        >>> [round(float(h) * 1e3, 1) for h in out.wear]  # [um]
        [3.8, 7.3]
        >>> out.valid.tolist()
        [True, True]
        """
        p2p, kurtosis = np.broadcast_arrays(np.asarray(p2p, float), np.asarray(kurtosis, float))
        if np.any(~np.isfinite(p2p)) or np.any(~np.isfinite(kurtosis)):
            raise ValueError("peak-to-peak and kurtosis must be finite; drop or repair the rows "
                             "with NaN or infinite features first")
        if self.p2p_tol <= 0 or self.kurtosis_tol <= 0:
            raise ValueError("tolerances must be > 0: build the estimator with fit() or "
                             "from_config()")
        grid = self._grid()
        n = grid / self.cycles_unit
        pg, kg = np.polyval(self.p2p_cubic, n), np.polyval(self.kurtosis_cubic, n)
        flat_p, flat_k = p2p.ravel(), kurtosis.ravel()
        best = np.empty(flat_p.shape)
        for lo in range(0, flat_p.size, chunk):
            sl = slice(lo, lo + chunk)
            cost = (((pg[None, :] - flat_p[sl, None]) / self.p2p_tol) ** 2
                    + ((kg[None, :] - flat_k[sl, None]) / self.kurtosis_tol) ** 2)
            i = np.clip(np.argmin(cost, axis=1), 1, grid.size - 2)
            rows = np.arange(cost.shape[0])
            c0, c1, c2 = cost[rows, i - 1], cost[rows, i], cost[rows, i + 1]
            denom = c0 - 2 * c1 + c2
            shift = np.where(denom > 0, 0.5 * (c0 - c2) / np.where(denom > 0, denom, 1), 0.0)
            best[sl] = np.clip(grid[i] + np.clip(shift, -1, 1) * (grid[1] - grid[0]),
                               0.0, self.cycles_max)
        n_best = best / self.cycles_unit
        res_p = np.abs(np.polyval(self.p2p_cubic, n_best) - flat_p)
        res_k = np.abs(np.polyval(self.kurtosis_cubic, n_best) - flat_k)
        consistent = (res_p <= self.p2p_tol) & (res_k <= self.kurtosis_tol)
        in_range = ((flat_p >= pg.min() - self.p2p_tol) & (flat_p <= pg.max() + self.p2p_tol)
                    & (flat_k >= kg.min() - self.kurtosis_tol)
                    & (flat_k <= kg.max() + self.kurtosis_tol))
        shape = p2p.shape
        return Estimate(self.wear_at(best).reshape(shape), best.reshape(shape),
                        consistent.reshape(shape), in_range.reshape(shape))


def _fit_law(cycles: np.ndarray, wear: np.ndarray) -> np.ndarray:
    """The empirical two-exponential law of 4.1 fitted to all the given points."""
    from physics.dynamics.evolution import CANDIDATES, fit_evolution_model

    model = next(m for m in CANDIDATES if m.name == "empirical")
    scale_n, scale_h = 1e7, float(np.max(np.abs(wear))) or 1.0
    theta, coef = fit_evolution_model(model, cycles / scale_n, wear / scale_h)
    return np.array([coef[0] * scale_h, theta[0] / scale_n, coef[1] * scale_h,
                     theta[1] / scale_n])


def wear_errors(predicted: np.ndarray, true: np.ndarray) -> dict[str, float]:
    """RMSE, R^2, maximum and mean relative error (over rows with nonzero true wear) [%].

    The thesis's figure of merit (4.4), "accuracy", is ``100 - mean relative error``.
    """
    predicted, true = np.asarray(predicted, float), np.asarray(true, float)
    err = predicted - true
    ss_tot = float(np.sum((true - true.mean()) ** 2))
    nz = true != 0
    rel = np.abs(err[nz]) / np.abs(true[nz]) * 100
    return {
        "rmse": float(np.sqrt(np.mean(err**2))),
        "r2": float(1 - np.sum(err**2) / ss_tot) if ss_tot > 0 else float("nan"),
        "max_relative_error_pct": float(rel.max()) if rel.size else float("nan"),
        "mean_relative_error_pct": float(rel.mean()) if rel.size else float("nan"),
        "accuracy_pct": float(100 - rel.mean()) if rel.size else float("nan"),
    }


def accuracy(estimate: Estimate, wear_true: np.ndarray) -> dict[str, float]:
    """:func:`wear_errors` of an estimate, with the counts of flagged rows."""
    return {**wear_errors(estimate.wear, wear_true),
            "inconsistent_rows": int(np.sum(~estimate.consistent)),
            "out_of_range_rows": int(np.sum(~estimate.in_range))}
