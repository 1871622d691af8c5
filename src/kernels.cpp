// thetasol.core._kernels (re-exported by thetasol.core.kernels): the compiled per-time evaluation of the theta-function rotation.
//
// The Python side (thetasol.theta.flow.FlowTheta, thetasol.solutions.rotation.theta_rotation.evaluator) builds
// every table once and validates the times; this file only computes from those frozen arrays:
// turns -> phases -> Fourier flow tables -> [theta | d theta/dt] along the flow -> the state (omega, Q).
// Each step repeats the floating-point operations of the numpy oracle (tests/oracle_theta_evaluation.py)
// in the same order where the order is fixed (turns, tables, phase products, complex division), so the
// two agree to the rounding of the matrix products, whose summation order BLAS chooses.
// Built with -ffp-contract=off: fused multiply-adds would change the exact turns of core/turns.py.
#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>
#include <nanobind/stl/tuple.h>

#include <cmath>
#include <algorithm>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

namespace nb = nanobind;

namespace {

using In1 = nb::ndarray<const double, nb::ndim<1>, nb::c_contig, nb::device::cpu>;
using In2 = nb::ndarray<const double, nb::ndim<2>, nb::c_contig, nb::device::cpu>;
using InI2 = nb::ndarray<const int64_t, nb::ndim<2>, nb::c_contig, nb::device::cpu>;
using InI1 = nb::ndarray<const int64_t, nb::ndim<1>, nb::c_contig, nb::device::cpu>;

// Below this |t| the products of rint(t) with 22-bit pieces are exact (thetasol.core.turns.TURNS_EXACT).
constexpr double TURNS_EXACT = 2147483648.0;
// Times per block of the product with W, and rows of W per partial sum.
constexpr size_t BLOCK = 4;
constexpr size_t SPAN = 32;
// 2 pi as numpy's 2 * math.pi: exp(2 pi i x) of the turns x.
constexpr double TWO_PI = 2.0 * 3.141592653589793;

struct Cx {
    double re, im;
};

// numpy's complex product (re: ac - bd, im: ad + bc), without std::complex's NaN recovery.
inline Cx mul(Cx a, Cx b) { return {a.re * b.re - a.im * b.im, a.re * b.im + a.im * b.re}; }

// numpy's complex quotient (Smith's algorithm, as numpy's loops compute it).
inline Cx div(Cx a, Cx b) {
    const double ar = std::fabs(b.re), ai = std::fabs(b.im);
    if (ar >= ai) {
        if (ar == 0.0 && ai == 0.0) return {a.re / ar, a.im / ai};
        const double rat = b.im / b.re, scl = 1.0 / (b.re + b.im * rat);
        return {(a.re + a.im * rat) * scl, (a.im - a.re * rat) * scl};
    }
    const double rat = b.re / b.im, scl = 1.0 / (b.im + b.re * rat);
    return {(a.re * rat + a.im) * scl, (a.im * rat - a.re) * scl};
}

// exp(2 pi i x) of real turns x.
inline Cx turn(double x) {
    const double y = x * TWO_PI;
    return {std::cos(y), std::sin(y)};
}

// The turns c t of one rate c = c1 + c2 + c3 (float value c), up to integers (thetasol.core.turns.rate_turns).
inline double rate_turn(double t1, double t2, double c1, double c2, double c3, double c) {
    double x = c1 * t1;
    x -= std::nearbyint(x);
    double y = c2 * t1;
    y -= std::nearbyint(y);
    x += y;
    x += c3 * t1;
    x += c * t2;
    return x;
}

// t = t1 + t2 with t1 = rint(t), or t1 = 0 for |t| >= 2^31.
inline void split_time(double t, double& t1, double& t2) {
    t1 = std::nearbyint(t);
    if (std::fabs(t1) >= TURNS_EXACT) t1 = 0.0;
    t2 = t - t1;
}

void need(bool ok, const std::string& what) {
    if (!ok) throw std::invalid_argument("thetasol.core.kernels: " + what);
}

// theta(s_j + t u) along the real flow as the Fourier series of thetasol.theta.flow.FlowTheta: per time the
// r turns t u mod 1, the tables exp(2 pi i k phi_i) as powers outwards from k = 0, the products over the r
// phases for each mode p, and the real matrix W (2P, 4S) from (cos, sin) of the modes to [v | dv].
class FlowKernel {
public:
    FlowKernel(In2 u_pieces, InI1 lo, InI1 span, InI2 modes, In2 W) {
        r_ = static_cast<size_t>(u_pieces.shape(1));
        need(u_pieces.shape(0) == 4, "u_pieces must be (4, r)");
        need(lo.shape(0) == r_ && span.shape(0) == r_ && modes.shape(1) == r_, "lo, span, modes must have r columns");
        P_ = static_cast<size_t>(modes.shape(0));
        need(W.shape(0) == 2 * P_ && W.shape(1) % 4 == 0, "W must be (2 P, 4 S)");
        cols_ = static_cast<size_t>(W.shape(1));
        u_.assign(u_pieces.data(), u_pieces.data() + 4 * r_);
        W_.assign(W.data(), W.data() + 2 * P_ * cols_);
        size_t start = 0;
        for (size_t i = 0; i < r_; ++i) {
            need(lo(i) <= 0 && span(i) >= 1 - lo(i), "every table must hold k = 0");
            start_.push_back(start);
            zero_.push_back(start + static_cast<size_t>(-lo(i)));
            start += static_cast<size_t>(span(i));
        }
        start_.push_back(start);
        ntab_ = start;
        gather_.resize(P_ * r_);
        for (size_t p = 0; p < P_; ++p)
            for (size_t i = 0; i < r_; ++i) {
                const int64_t k = modes(p, i);
                need(k >= 0 && k < span(i), "modes must index their tables");
                gather_[p * r_ + i] = start_[i] + static_cast<size_t>(k);
            }
    }

    size_t columns() const { return cols_; }
    size_t table_size() const { return ntab_; }

    // exp(2 pi i p.phi) of the modes at the time t as floats (2 P); tab (table_size) is work space.
    void phases(double t, Cx* tab, double* ph) const {
        double t1, t2;
        split_time(t, t1, t2);
        for (size_t i = 0; i < r_; ++i) {
            double x = rate_turn(t1, t2, u_[i], u_[r_ + i], u_[2 * r_ + i], u_[3 * r_ + i]);
            x -= std::nearbyint(x);
            const Cx e = turn(x), ec = {e.re, -e.im};
            const size_t z = zero_[i];
            tab[z] = {1.0, 0.0};
            if (z + 1 < start_[i + 1]) tab[z + 1] = e;
            for (size_t k = z + 2; k < start_[i + 1]; ++k) tab[k] = mul(tab[k - 1], e);
            if (z > start_[i]) {
                tab[z - 1] = ec;
                for (size_t k = z - 1; k > start_[i]; --k) tab[k - 1] = mul(tab[k], ec);
            }
        }
        for (size_t p = 0; p < P_; ++p) {
            const size_t* g = &gather_[p * r_];
            Cx x = tab[g[0]];
            for (size_t i = 1; i < r_; ++i) x = mul(x, tab[g[i]]);
            ph[2 * p] = x.re;
            ph[2 * p + 1] = x.im;
        }
    }

    // [v | dv] as floats (n, cols) at the n <= BLOCK times t; work: work_size() doubles.
    void values(const double* t, size_t n, double* work, double* out) const {
        Cx* tab = reinterpret_cast<Cx*>(work);
        double* ph = work + 2 * ntab_;
        for (size_t b = 0; b < n; ++b) phases(t[b], tab, ph + b * 2 * P_);
        product(ph, n, out);
    }

    // work space of values(): the tables and the phases of a block of times
    size_t work_size() const { return 2 * ntab_ + BLOCK * 2 * P_; }

    // [v | dv] (n, cols) at the times t (n,).
    nb::ndarray<nb::numpy, double, nb::ndim<2>> batch(In1 t) const {
        const size_t n = static_cast<size_t>(t.shape(0));
        double* out = new double[n * cols_ + (n == 0)];
        nb::capsule owner(out, [](void* p) noexcept { delete[] static_cast<double*>(p); });
        {
            nb::gil_scoped_release release;
            std::vector<double> work(work_size());
            const double* tt = t.data();
            for (size_t m = 0; m < n; m += BLOCK)
                values(tt + m, std::min(BLOCK, n - m), work.data(), out + m * cols_);
        }
        return nb::ndarray<nb::numpy, double, nb::ndim<2>>(out, {n, cols_}, owner);
    }

private:
    // out (n, cols) = ph (BLOCK, 2 P) @ W: AVX2 with FMA where the processor has it (chosen at run
    // time; the wheel itself assumes only x86-64), else the same blocked sums in SSE2
    void product(const double* ph, size_t n, double* out) const {
#if defined(__GNUC__) && (defined(__x86_64__) || defined(__i386__))
        static const bool avx2 = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
        if (avx2) return product_avx2(ph, n, out);
#endif
        if (n == BLOCK) return product_blocked<BLOCK, 2>(ph, n, out);
        for (size_t b = 0; b < n; ++b) product_blocked<1, 10>(ph + b * 2 * P_, 1, out + b * cols_);
    }

#if defined(__GNUC__) && (defined(__x86_64__) || defined(__i386__))
    // (contracted to fused multiply-adds here only: the turns and the state keep -ffp-contract=off)
    __attribute__((target("avx2,fma"), optimize("fp-contract=fast"))) void product_avx2(const double* ph, size_t n,
                                                                                         double* out) const {
        if (n == BLOCK) return product_blocked<BLOCK, 2>(ph, n, out);
        for (size_t b = 0; b < n; ++b) product_blocked<1, 10>(ph + b * 2 * P_, 1, out + b * cols_);
    }
#endif

    // Register-blocked product: NB times x 4 NV columns of accumulators (NB NV <= 10 vectors), each summing
    // SPAN rows of W from zero before it joins the column's total: the rounding grows with SPAN + 2 P / SPAN
    // terms, not 2 P.  Each column's sums are the same operations whatever NB, NV and the other times of
    // the block, so a time alone (NB = 1, wide rows of columns instead) gives the bits it gets in a batch.
    template <size_t NB, size_t NV>
    __attribute__((always_inline)) inline void product_blocked(const double* ph, size_t n, double* out) const {
        typedef double v4 __attribute__((vector_size(32)));
        constexpr size_t CW = 4 * NV;
        const size_t rows = 2 * P_;
        double total[NB][CW];
        for (size_t j0 = 0; j0 < cols_; j0 += CW) {
            const size_t width = std::min<size_t>(CW, cols_ - j0);
            double wpad[CW] = {};
            for (size_t b = 0; b < NB; ++b)
                for (size_t j = 0; j < CW; ++j) total[b][j] = 0.0;
            for (size_t q0 = 0; q0 < rows; q0 += SPAN) {
                const size_t q1 = std::min(rows, q0 + SPAN);
                v4 acc[NB][NV] = {};
                for (size_t q = q0; q < q1; ++q) {
                    const double* w = &W_[q * cols_ + j0];
                    if (width < CW) {
                        for (size_t j = 0; j < width; ++j) wpad[j] = w[j];
                        w = wpad;
                    }
                    v4 wv[NV];
#pragma GCC unroll 16
                    for (size_t k = 0; k < NV; ++k) __builtin_memcpy(&wv[k], w + 4 * k, sizeof(v4));
#pragma GCC unroll 4
                    for (size_t b = 0; b < NB; ++b) {
                        const double a = ph[b * rows + q];
                        const v4 av = {a, a, a, a};
#pragma GCC unroll 16
                        for (size_t k = 0; k < NV; ++k) acc[b][k] += av * wv[k];   // fused where contracted
                    }
                }
                for (size_t b = 0; b < NB; ++b)
                    for (size_t k = 0; k < NV; ++k)
                        for (size_t j = 0; j < 4; ++j) total[b][4 * k + j] += acc[b][k][j];
            }
            for (size_t b = 0; b < n; ++b)
                for (size_t j = 0; j < width; ++j) out[b * cols_ + j0 + j] = total[b][j];
        }
    }

private:
    size_t r_ = 0, P_ = 0, cols_ = 0, ntab_ = 0;
    std::vector<double> u_, W_;
    std::vector<size_t> start_, zero_, gather_;
};

// The state (omega, Q) of the theta-function rotation (thetasol.solutions.rotation.theta_rotation.evaluator):
// the nine exponents exp(i nu_sk t) from exact turns of a few rates, Psi and its rate from the flow's
// values, one real product with the folded linear map (45, 36), one Newton-Schulz step to the polar
// factor, vee(F Fd^T), and for a symmetric body the turning frame.
class RotationKernel {
public:
    RotationKernel(const FlowKernel& flow, In2 pieces, In2 coef, InI1 row_of, In2 amp, In2 nu, In2 lin, In2 P,
                   double spin, int axis, double ns_max)
        : flow_(flow), spin_(spin), axis_(axis), ns_max_(ns_max) {
        need(flow.columns() == 40, "the flow must carry 10 shifts (9 b_sk and d)");
        need(pieces.shape(0) == 4, "pieces must be (4, rates)");
        rates_ = static_cast<size_t>(pieces.shape(1));
        need(coef.shape(0) <= 9 && coef.shape(1) == rates_ && row_of.shape(0) == 9,
             "coef must be (rows <= 9, rates), row_of (9,)");
        need(amp.shape(0) == 9 && amp.shape(1) == 2, "amp must be the float view (9, 2) of the 3x3 amplitudes");
        need(nu.shape(0) == 3 && nu.shape(1) == 3 && P.shape(0) == 3 && P.shape(1) == 3, "nu and P must be 3x3");
        need(lin.shape(0) == 45 && lin.shape(1) == 36, "lin must be (45, 36)");
        need(axis >= -1 && axis <= 2, "axis must be -1 (distinct J) or 0, 1, 2");
        pieces_.assign(pieces.data(), pieces.data() + 4 * rates_);
        const size_t rows = static_cast<size_t>(coef.shape(0));
        for (size_t q = 0; q < rows; ++q) {
            std::vector<std::pair<size_t, double>> terms;
            for (size_t j = 0; j < rates_; ++j)
                if (coef(q, j) != 0.0) terms.emplace_back(j, coef(q, j));
            terms_.push_back(terms);
        }
        for (size_t m = 0; m < 9; ++m) {
            need(row_of(m) >= 0 && static_cast<size_t>(row_of(m)) < rows, "row_of must index the rows");
            row_of_[m] = static_cast<size_t>(row_of(m));
            amp_[m] = {amp(m, 0), amp(m, 1)};
            nu_[m] = nu.data()[m];
        }
        linT_.resize(36 * 45);
        for (size_t i = 0; i < 45; ++i)
            for (size_t k = 0; k < 36; ++k) linT_[k * 45 + i] = lin(i, k);
        for (size_t a = 0; a < 9; ++a) P_[a] = P.data()[a];
    }

    // omega (3), Q (9, row-major) at t from the flow's values vd (40); returns whether the Newton-Schulz step applied (else Q is the
    // unprojected matrix in the output frame, for the caller's SVD).
    bool state(double t, const double* vd, double* x, double* w, double* Q) const {
        const Cx* v = reinterpret_cast<const Cx*>(vd);
        const Cx* dv = v + 10;
        double t1, t2;
        split_time(t, t1, t2);
        for (size_t j = 0; j < rates_; ++j)
            x[j] = rate_turn(t1, t2, pieces_[j], pieces_[rates_ + j], pieces_[2 * rates_ + j], pieces_[3 * rates_ + j]);
        const Cx ivd = div({1.0, 0.0}, v[9]);
        const Cx dd = mul(dv[9], ivd);
        // exp(i nu t) on the distinct rows of turns only (exponents alike by symmetry share one)
        Cx ex[9];
        for (size_t q = 0; q < terms_.size(); ++q) {
            double row = 0.0;
            for (const auto& term : terms_[q]) row += x[term.first] * term.second;
            ex[q] = turn(row);
        }
        double Z[36];
        for (size_t m = 0; m < 9; ++m) {
            Cx q = mul(ex[row_of_[m]], amp_[m]);
            q = mul(q, ivd);
            const Cx z0 = mul(q, v[m]);
            Cx rate = {0.0 - dd.re, nu_[m] - dd.im};
            rate = mul(rate, v[m]);
            rate.re += dv[m].re;
            rate.im += dv[m].im;
            const Cx z1 = mul(q, rate);
            Z[2 * m] = z0.re;
            Z[2 * m + 1] = z0.im;
            Z[18 + 2 * m] = z1.re;
            Z[18 + 2 * m + 1] = z1.im;
        }
        // Y = lin Z, column by column of lin (stored transposed): each Y[i] sums over k in order, and
        // the loop over i vectorizes
        double Y[45] = {};
        for (size_t k = 0; k < 36; ++k) {
            const double* L = &linT_[k * 45];
            const double z = Z[k];
            for (size_t i = 0; i < 45; ++i) Y[i] += L[i] * z;
        }
        // polar factor of X = Y[:9] (3x3, rows r, columns c): X (1 - D / 2), D = X^T X - 1
        const double* X = Y;
        double D[9];
        bool ok = true;  // false also where D is NaN
        for (size_t a = 0; a < 3; ++a)
            for (size_t b = 0; b < 3; ++b) {
                double s = X[a] * X[b] + X[3 + a] * X[3 + b];
                s += X[6 + a] * X[6 + b];
                s -= (a == b) ? 1.0 : 0.0;
                D[3 * a + b] = s;
                ok = ok && std::fabs(s) <= ns_max_;
            }
        double G[9];
        for (size_t r = 0; r < 3; ++r)
            for (size_t c = 0; c < 3; ++c) {
                if (!ok) {
                    G[3 * r + c] = X[3 * r + c];
                    continue;
                }
                double s = 0.0;
                for (size_t k = 0; k < 3; ++k) s += X[3 * r + k] * (((k == c) ? 1.0 : 0.0) - 0.5 * D[3 * k + c]);
                G[3 * r + c] = s;
            }
        double om[3];
        for (size_t a = 0; a < 3; ++a) {
            double s = 0.0;
            for (size_t c = 0; c < 3; ++c) s += Y[27 + 3 * a + c] * Y[9 + 3 * a + c] - Y[36 + 3 * a + c] * Y[18 + 3 * a + c];
            om[a] = s;
        }
        if (axis_ < 0) {
            for (size_t a = 0; a < 9; ++a) Q[a] = G[a];
            for (size_t a = 0; a < 3; ++a) w[a] = om[a];
            return ok;
        }
        // symmetric body: Q = Q~ R^T P^T, omega = P (R omega~ + spin e), R = exp(-spin t hat(e))
        const size_t ax = static_cast<size_t>(axis_), i = (ax + 1) % 3, j = (ax + 2) % 3;
        const double c = std::cos(-spin_ * t), s = std::sin(-spin_ * t);
        double Qr[9], wr[3];
        for (size_t r = 0; r < 3; ++r) {
            Qr[3 * r + ax] = G[3 * r + ax];
            Qr[3 * r + i] = c * G[3 * r + i] - s * G[3 * r + j];
            Qr[3 * r + j] = s * G[3 * r + i] + c * G[3 * r + j];
        }
        wr[ax] = om[ax] + spin_;
        wr[i] = c * om[i] - s * om[j];
        wr[j] = s * om[i] + c * om[j];
        for (size_t r = 0; r < 3; ++r)
            for (size_t a = 0; a < 3; ++a) {
                double acc = 0.0;
                for (size_t k = 0; k < 3; ++k) acc += P_[3 * a + k] * Qr[3 * r + k];
                Q[3 * r + a] = acc;
            }
        for (size_t a = 0; a < 3; ++a) {
            double acc = 0.0;
            for (size_t k = 0; k < 3; ++k) acc += P_[3 * a + k] * wr[k];
            w[a] = acc;
        }
        return ok;
    }

    // (omega (n, 3), Q (n, 3, 3), projected (n,) bool) at the times t (n,).
    nb::tuple batch(In1 t) const {
        const size_t n = static_cast<size_t>(t.shape(0));
        double* w = new double[3 * n + 1];
        double* Q = new double[9 * n + 1];
        bool* ok = new bool[n + 1];
        nb::capsule ow(w, [](void* p) noexcept { delete[] static_cast<double*>(p); });
        nb::capsule oQ(Q, [](void* p) noexcept { delete[] static_cast<double*>(p); });
        nb::capsule ook(ok, [](void* p) noexcept { delete[] static_cast<bool*>(p); });
        {
            nb::gil_scoped_release release;
            std::vector<double> work(flow_.work_size()), x(rates_);
            double vd[BLOCK * 40];
            const double* tt = t.data();
            for (size_t m0 = 0; m0 < n; m0 += BLOCK) {
                const size_t nb = std::min(BLOCK, n - m0);
                flow_.values(tt + m0, nb, work.data(), vd);
                for (size_t m = m0; m < m0 + nb; ++m)
                    ok[m] = state(tt[m], vd + (m - m0) * 40, x.data(), w + 3 * m, Q + 9 * m);
            }
        }
        return nb::make_tuple(nb::ndarray<nb::numpy, double, nb::ndim<2>>(w, {n, 3}, ow),
                              nb::ndarray<nb::numpy, double, nb::ndim<3>>(Q, {n, 3, 3}, oQ),
                              nb::ndarray<nb::numpy, bool, nb::ndim<1>>(ok, {n}, ook));
    }

private:
    FlowKernel flow_;
    double spin_;
    int axis_;
    double ns_max_;
    size_t rates_ = 0;
    std::vector<double> pieces_, linT_;
    std::vector<std::vector<std::pair<size_t, double>>> terms_;
    size_t row_of_[9];
    Cx amp_[9];
    double nu_[9], P_[9];
};

}  // namespace

NB_MODULE(_kernels, m) {
    m.doc() = "The compiled per-time evaluation of the theta-function rotation (built from frozen tables).";
    // Solutions held in module-level caches (the reference catalogue, the tests' fixtures) still own their
    // kernels when the interpreter exits; nanobind would report them as leaks, which they are not.
    nb::set_leak_warnings(false);
    nb::class_<FlowKernel>(m, "FlowKernel",
                           "theta(s_j + t u) along a real flow as a Fourier series (thetasol.theta.flow.FlowTheta).")
        .def(nb::init<In2, InI1, InI1, InI2, In2>(), nb::arg("u_pieces"), nb::arg("lo"), nb::arg("span"),
             nb::arg("modes"), nb::arg("W"))
        .def("__call__", &FlowKernel::batch, nb::arg("t"), "[v | dv] as floats (n, 4 S) at the flat times t.");
    nb::class_<RotationKernel>(m, "RotationKernel",
                               "The state (omega, Q) of the theta-function rotation at many times.")
        .def(nb::init<const FlowKernel&, In2, In2, InI1, In2, In2, In2, In2, double, int, double>(),
             nb::arg("flow"), nb::arg("pieces"), nb::arg("coef"), nb::arg("row_of"), nb::arg("amp"), nb::arg("nu"),
             nb::arg("lin"), nb::arg("P"), nb::arg("spin"), nb::arg("axis"), nb::arg("ns_max"))
        .def("__call__", &RotationKernel::batch, nb::arg("t"),
             "(omega (n, 3), Q (n, 3, 3), projected (n,)) at the flat times t.");
}
