//! Gauss–Legendre quadrature, used once per lobe width to build [`crate::lobe::LobeTable`].

/// Nodes and weights of an n-point Gauss–Legendre rule on [−1, 1].
#[derive(Clone, Debug)]
pub(crate) struct GaussLegendre {
    nodes: Vec<f64>,
    weights: Vec<f64>,
}

impl GaussLegendre {
    /// Builds the n-point rule by Newton iteration on the Legendre polynomial P_n.
    pub(crate) fn new(n: usize) -> Self {
        assert!(n >= 1, "a quadrature rule needs at least one node");
        let mut nodes = vec![0.0; n];
        let mut weights = vec![0.0; n];
        let nf = n as f64;
        for i in 0..n.div_ceil(2) {
            // Tricomi's approximation is close enough for Newton to converge to root i.
            let mut x = (std::f64::consts::PI * (i as f64 + 0.75) / (nf + 0.5)).cos();
            let mut dp = 1.0;
            for _ in 0..100 {
                let (p, d) = legendre(n, x);
                dp = d;
                let dx = p / d;
                x -= dx;
                if dx.abs() < 1e-16 {
                    break;
                }
            }
            let (_, d) = legendre(n, x);
            if d.is_finite() {
                dp = d;
            }
            let w = 2.0 / ((1.0 - x * x) * dp * dp);
            nodes[i] = -x;
            nodes[n - 1 - i] = x;
            weights[i] = w;
            weights[n - 1 - i] = w;
        }
        Self { nodes, weights }
    }

    /// ∫ₐᵇ f(x) dx. The nodes are interior, so f is never evaluated at a or b.
    pub(crate) fn integrate(&self, a: f64, b: f64, mut f: impl FnMut(f64) -> f64) -> f64 {
        if b <= a {
            return 0.0;
        }
        let half = 0.5 * (b - a);
        let mid = 0.5 * (a + b);
        let sum: f64 = self
            .nodes
            .iter()
            .zip(&self.weights)
            .map(|(&x, &w)| w * f(mid + half * x))
            .sum();
        half * sum
    }
}

/// P_n(x) and P_n'(x) by the three-term recurrence.
fn legendre(n: usize, x: f64) -> (f64, f64) {
    let (mut p0, mut p1) = (1.0, x);
    for k in 2..=n {
        let kf = k as f64;
        let p2 = ((2.0 * kf - 1.0) * x * p1 - (kf - 1.0) * p0) / kf;
        p0 = p1;
        p1 = p2;
    }
    let p = if n == 0 { 1.0 } else { p1 };
    let d = n as f64 * (x * p - p0) / (x * x - 1.0);
    (p, d)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn integrates_polynomials_exactly() {
        let gl = GaussLegendre::new(8);
        // Degree 15 is the highest an 8-point rule integrates exactly.
        let got = gl.integrate(0.0, 2.0, |x| x.powi(15));
        let want = 2f64.powi(16) / 16.0;
        assert!((got / want - 1.0).abs() < 1e-13, "{got} vs {want}");
        let odd = GaussLegendre::new(7);
        let got = odd.integrate(-1.0, 3.0, |x| x * x);
        assert!((got - 28.0 / 3.0).abs() < 1e-12);
    }

    #[test]
    fn integrates_smooth_functions() {
        let gl = GaussLegendre::new(24);
        let got = gl.integrate(0.0, std::f64::consts::PI, f64::sin);
        assert!((got - 2.0).abs() < 1e-13, "{got}");
    }
}
