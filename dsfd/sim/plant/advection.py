"""Second-order upwind correction of the vertical advection in the cavity
(docs/model.md#plant-layout).

The base scheme is the first-order upwind (docs/model.md#plant-layout), written as advective links:
segment k receives ṁ c_p (T_{k−1} − T_k). Its numerical diffusion makes the cavity air
(and with it the panes, the louver and the stack pressure) converge only to first order in
δz = H_g/N: in sunny regime-1 runs the mid-height states and the outlet air change by
≈ 0.3 K between N = 10 and N = 20. ``advection='upwind2'`` adds, per sub-column, the
difference between limited second-order face values and the first-order ones:

    T_f(k+½) = T_k + C_{k+1},   C_{k+1} = ½ L(T_k − T_{k−1}, T_{k+1} − T_k),
    L(a, b) = a b (a + b)/(a² + b² + ε²)            (van Albada limiter, smooth form)

(upwind direction; the inlet face carries the inflow temperature exactly, C_0 = 0). The
cell balances gain ṁ c_p (C_k − C_{k+1}); the correction at the outlet face goes to the
downstream plenum or leaves with the outflow. The corrections telescope, so energy stays
conserved. References: G. D. van Albada, B. van Leer, W. W. Roberts, Astron. Astrophys. 108
(1982) 76–84; S. V. Patankar, *Numerical Heat Transfer and Fluid Flow* (1980), ch. 5.
"""

from __future__ import annotations

import numpy as np

from dsfd.sim.plant.layout import Layout

#: ε² of the limiter denominator [K²].
_EPS2 = 1e-10


def limiter(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Smooth van Albada limited slope a b (a + b)/(a² + b² + ε²) [K]."""
    return a * b * (a + b) / (a * a + b * b + _EPS2)


class Advection2:
    """Correction heat flows of the second-order upwind advection for one plant layout."""

    def __init__(self, lay: Layout) -> None:
        subs = ("ao", "ai") if lay.split else ("ao",)
        self.nn = lay.n_nodes
        self.n = lay.n
        self.cols = np.stack([lay.idx(k) for k in subs])  # (n_sub, N), bottom → top
        self.share = 1.0 / len(subs)
        self.pb = lay.pb if lay.plenums else None
        self.pt = lay.pt if lay.plenums else None
        self._orders = {d: self._order(d) for d in (1, -1)}
        self._ext = {d: np.empty((self.cols.shape[0], self.n + 2)) for d in (1, -1)}

    def _order(self, direction: int) -> tuple[np.ndarray, int | None, int | None]:
        cols = self.cols if direction > 0 else self.cols[:, ::-1]
        inlet, outlet = (self.pb, self.pt) if direction > 0 else (self.pt, self.pb)
        return cols, inlet, outlet

    def corrections(self, T: np.ndarray, m_cp: float, t_inflow: float
                    ) -> tuple[np.ndarray, float]:
        """Correction heat flows [W] per node and the outlet-face correction [K].

        Parameters
        ----------
        T : array (n_nodes,), [K]
        m_cp : float, [W/K]
            Net upward cavity flow × c_p (its sign gives the direction).
        t_inflow : float, [K]
            Temperature entering the first segment when there is no inlet plenum (mixed
            opening inflows).
        """
        direction = 1 if m_cp > 0 else -1
        cols, inlet, outlet = self._orders[direction]
        ms = abs(m_cp) * self.share
        n = self.n
        ext = self._ext[direction]
        ext[:, 1:n + 1] = T[cols]
        ext[:, 0] = T[inlet] if inlet is not None else t_inflow
        if outlet is not None:
            ext[:, n + 1] = T[outlet]
        else:  # linear extrapolation beyond the last segment
            ext[:, n + 1] = 2.0 * ext[:, n] - ext[:, n - 1]
        diff = ext[:, 1:] - ext[:, :-1]
        a, b = diff[:, :n], diff[:, 1:]
        face = 0.5 * a * b * (a + b) / (a * a + b * b + _EPS2)
        flux = ms * face  # through the outflow face of each cell [W]
        q = np.zeros(self.nn)
        q[cols[:, 0]] = -flux[:, 0]
        q[cols[:, 1:]] = flux[:, :-1] - flux[:, 1:]
        if outlet is not None:
            q[outlet] += flux[:, -1].sum()
        return q, float(face[:, -1].mean())

    def jacobian(self, T: np.ndarray, m_cp: float, cap: np.ndarray) -> np.ndarray:
        """Exact Jacobian of the corrections [1/s], shape (nn, nn) (inflow held fixed)."""
        direction = 1 if m_cp > 0 else -1
        cols, inlet, outlet = self._order(direction)
        ms = abs(m_cp) * self.share
        nn = self.nn
        jac = np.zeros((nn, nn))
        for c in cols:
            n = c.size
            nodes = [-1 if inlet is None else inlet, *c.tolist()]
            ext = np.empty(n + 2)
            ext[0] = T[nodes[0]] if nodes[0] >= 0 else T[c[0]]
            ext[1:n + 1] = T[c]
            if outlet is not None:
                ext[n + 1] = T[outlet]
            else:
                ext[n + 1] = 2.0 * ext[n] - ext[n - 1]
            d = np.diff(ext)
            a, b = d[:n], d[1:]
            den = a * a + b * b + _EPS2
            num = a * b * (a + b)
            la = ((2 * a * b + b * b) * den - num * 2 * a) / (den * den)
            lb = ((a * a + 2 * a * b) * den - num * 2 * b) / (den * den)
            for j in range(1, n + 1):  # face after the cell at ext index j
                w = {j - 1: -0.5 * la[j - 1], j: 0.5 * (la[j - 1] - lb[j - 1]),
                     j + 1: 0.5 * lb[j - 1]}
                if outlet is None and j + 1 == n + 1:  # extrapolated neighbour
                    wx = w.pop(n + 1)
                    w[n] = w.get(n, 0.0) + 2.0 * wx
                    w[n - 1] = w.get(n - 1, 0.0) - wx
                targets = [(c[j - 1], -ms)]
                if j < n:
                    targets.append((c[j], ms))
                elif outlet is not None:
                    targets.append((outlet, ms))
                for e, wv in w.items():
                    col = nodes[e] if e <= n else outlet
                    if col is None or col < 0:
                        continue
                    for row, sign in targets:
                        jac[row, col] += sign * wv / cap[row]
        return jac
