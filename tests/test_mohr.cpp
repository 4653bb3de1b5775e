// Mohr-Coulomb soil (FLAC's closed-form return), softening, scatter and the Jaumann
// rotation, driven one point at a time along strain paths with known answers.
#include <doctest/doctest.h>

#include <Eigen/Dense>
#include <cmath>
#include <cstring>
#include <limits>
#include <vector>

#include "../lpfdm.hpp"
#include "common.hpp"

using namespace lpfdm;

namespace {

// Principal stresses sig1 <= sig2 <= sig3 from an independent eigen-solver.
Eigen::Vector3d principal(const Stress& s) {
    Eigen::Matrix3d m;
    m << s.xx, s.xy, 0, s.xy, s.yy, 0, 0, 0, s.zz;
    return Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(m).eigenvalues();  // ascending
}

struct Yield {
    double fs, ft;
};

Yield yield_functions(const Stress& s, double c, double phi_deg, double tension) {
    const Eigen::Vector3d p = principal(s);
    const double N = (1 + std::sin(phi_deg * kDeg)) / (1 - std::sin(phi_deg * kDeg));
    double st = phi_deg > 0 ? c / std::tan(phi_deg * kDeg) : 1e300;
    if (tension >= 0) st = std::min(st, tension);
    return {p(0) - p(2) * N + 2 * c * std::sqrt(N), st - p(2)};
}

MohrStrength strength(const MaterialConstants& k) { return {k.c, k.n_phi, k.n_psi, k.tension}; }

// Plastic strain increment d_eps - C d_sig (3D isotropic compliance, d_eps_zz = 0):
// returns {volumetric, max - min principal} of the plastic part.
std::pair<double, double> plastic_part(const Material& m, const StrainIncrement& d, const Stress& s0, const Stress& s1) {
    const double E = m.E, nu = m.nu;
    const double dxx = s1.xx - s0.xx, dyy = s1.yy - s0.yy, dxy = s1.xy - s0.xy, dzz = s1.zz - s0.zz, tr = dxx + dyy + dzz;
    Eigen::Matrix3d ep;
    const double exx = d.xx - ((1 + nu) * dxx - nu * tr) / E, eyy = d.yy - ((1 + nu) * dyy - nu * tr) / E;
    const double exy = 0.5 * d.gamma() - (1 + nu) * dxy / E, ezz = 0 - ((1 + nu) * dzz - nu * tr) / E;
    ep << exx, exy, 0, exy, eyy, 0, 0, 0, ezz;
    const Eigen::Vector3d ev = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(ep).eigenvalues();
    return {ev.sum(), ev(2) - ev(0)};
}

// One point in one cell of side 1 m, driven by prescribing the nodal increments.
struct OnePoint {
    Scene scene;
    Simulation sim;
    explicit OnePoint(const Material& m) : scene(make(m)), sim(scene) {}
    static Scene make(const Material& m) {
        Scene s;
        s.mx = 1; s.my = 1; s.cell_m = 1;
        s.materials.push_back(m);
        s.clusters.push_back({m.id, {0, 0, 1, 1}, 1, {}});
        s.dt_s = 1e-5; s.steps = 1;
        return s;
    }
    // Linear increment field du = G (x - x_p): the point stays where it is.
    void strain(double gxx, double gxy, double gyx, double gyy) {
        const double xp = sim.points().x[0], yp = sim.points().y[0];
        for (int j = 0; j <= 1; ++j)
            for (int i = 0; i <= 1; ++i) {
                const std::size_t n = std::size_t(sim.node(i, j));
                sim.du_x()[n] = gxx * (i - xp) + gxy * (j - yp);
                sim.du_y()[n] = gyx * (i - xp) + gyy * (j - yp);
            }
        sim.cell_strains();
        sim.update_points();
    }
    Stress stress() const {
        const Points& p = sim.points();
        return {p.sxx[0], p.syy[0], p.sxy[0], p.szz[0]};
    }
};

}  // namespace

TEST_CASE("unconfined plane-strain compression peaks at exactly 2c tan(45 + phi/2)") {
    for (double psi : {0.0, 10.0}) {
        const Material m = Material::mohr(1, 5e7, 0.3, 1700, 30, 9800, psi);
        const MaterialConstants k = constants_of(m);
        Stress s;
        double peak = 0;
        for (int step = 0; step < 400; ++step) {
            const double dyy = -2e-5;
            // sigma_xx = 0: find d_eps_xx by secant (the return is piecewise linear).
            auto trial = [&](double dxx, Stress& out) {
                out = s;
                const StrainIncrement d{dxx, dyy, 0, 0};
                elastic_increment(k, d, out);
                mohr_coulomb_return(k, strength(k), out);
                return out.xx;
            };
            Stress out;
            double x0 = -k.a2 / k.a1 * dyy, x1 = x0 * 1.01 + 1e-9, g0 = trial(x0, out), g1 = trial(x1, out);
            for (int it = 0; it < 30 && std::fabs(g1) > 1e-9; ++it) {
                const double x2 = x1 - g1 * (x1 - x0) / (g1 - g0);
                x0 = x1; g0 = g1; x1 = x2; g1 = trial(x1, out);
            }
            // The secant converged (it stops at 1e-9 Pa): a sigma_xx of 1e-8 Pa would move
            // sigma_yy by N_phi 1e-8 = 3e-8 Pa, the 1e-12 of the peak checked below.
            REQUIRE(std::fabs(g1) < 1e-8);
            s = out;
            peak = std::max(peak, -s.yy);
        }
        const double expect = 2 * 9800 * std::tan((45 + 15) * kDeg);
        CHECK(peak == approx(expect).epsilon(1e-12));
        CHECK(-s.yy == approx(expect).epsilon(1e-12));  // perfectly plastic: stays at the peak
    }
}

TEST_CASE("after every plastic correction the stress lies on the yield surface") {
    Random rnd(7);
    int plastic = 0, corners = 0, tension = 0;
    for (int trial = 0; trial < 20000; ++trial) {
        const double phi = 45 * rnd.uniform(), psi = phi * rnd.uniform(), c = 1e3 + 2e4 * rnd.uniform();
        const double tens = rnd.uniform() < 0.5 ? -1 : c * rnd.uniform();
        const Material m = Material::mohr(1, 5e7, 0.45 * rnd.uniform(), 1700, phi, c, psi, tens);
        const MaterialConstants k = constants_of(m);
        const double scale = 5 * c;
        Stress s{scale * (2 * rnd.uniform() - 1.5), scale * (2 * rnd.uniform() - 1.5), scale * (rnd.uniform() - 0.5),
                 scale * (2 * rnd.uniform() - 1.5)};
        const MohrResult r = mohr_coulomb_return(k, strength(k), s);
        const Yield f = yield_functions(s, c, phi, tens);
        // The return lands on its plane to rounding and accepts the others violated by 1e-11 of
        // its stresses and constants (the trial's principal stresses, 2c sqrt(N_phi), the tension
        // limit, which grows as c / tan(phi) for a small phi): 1e-9 of scale + c covers that
        // except below phi = 0.1 deg without a cut-off (0.2 % of the trials), where it holds
        // because the returns land to rounding (2e-15 of scale + c measured).
        const double tol = 1e-9 * (scale + c);
        CHECK(f.fs >= -tol);
        CHECK(f.ft >= -tol);
        if (r.mode != MohrResult::Elastic) {
            ++plastic;
            corners += r.mode == MohrResult::Edge;
            tension += r.mode == MohrResult::Tension;
            CHECK(std::min(std::fabs(f.fs), std::fabs(f.ft)) <= tol);
        }
    }
    MESSAGE(plastic << " plastic corrections, " << tension << " in tension, " << corners << " on an edge, corner or apex");
    CHECK(plastic > 5000);
    CHECK(corners > 100);
    CHECK(tension > 100);
}

TEST_CASE("with psi = phi every return, edges, corners and the apex included, is the projection in the energy norm") {
    // With associated flow the return of a trial t is the admissible stress s closest to t in
    // the norm of the compliance (a convex set's projection): (t - s) : C^-1 : (y - s) <= 0 for
    // every admissible y. The search for an edge, corner or apex tries the sets holding the
    // closed form's plane first; the projection is unique, so the order must not change it.
    // y: the returns of other trials (on the surface) and the corner of the tension planes,
    // all admissible. Tolerance: 1e-9 of the correction's own energy (round-off of a few
    // operations on the stresses), plus 1e-12 of the energy of stresses of the trials' scale;
    // a return with a wrong multiplier or flow rule breaks it by more than 1e8 times (tried).
    // Every fourth trial is a tension in all three directions beyond the tension limit:
    // those return to the apex (or the corner of a lower cut-off).
    Random rnd(41);
    int edges = 0, apex = 0, inside = 0;
    for (int k = 0; k < 300; ++k) {
        const double phi = 5 + 40 * rnd.uniform(), c = 1e3 + 2e4 * rnd.uniform();
        const double tens = k % 2 ? -1 : c * rnd.uniform();
        const Material m = Material::mohr(1, 5e7, 0.45 * rnd.uniform(), 1700, phi, c, phi, tens);
        const MaterialConstants mc = constants_of(m);
        const double scale = 5 * c;
        const double np = mc.n_phi, st = tens >= 0 ? std::min(2 * c * std::sqrt(np) / (np - 1), tens) : 2 * c * std::sqrt(np) / (np - 1);
        auto random_stress = [&]() {
            return Stress{scale * (2 * rnd.uniform() - 1.5), scale * (2 * rnd.uniform() - 1.5), scale * (rnd.uniform() - 0.5), scale * (2 * rnd.uniform() - 1.5)};
        };
        auto beyond_apex = [&]() {  // principal values all above st
            const double p = st + scale * (0.05 + rnd.uniform()), r = 0.5 * (p - st) * rnd.uniform(), a = 6.283185307179586 * rnd.uniform();
            return Stress{p + r * std::cos(a), p - r * std::cos(a), r * std::sin(a), st + (p - r - st) * rnd.uniform() + 1e-3 * scale};
        };
        std::vector<Stress> ys;
        for (int j = 0; j < 60; ++j) {
            Stress y = random_stress();
            mohr_coulomb_return(mc, strength(mc), y);
            ys.push_back(y);
        }
        ys.push_back({st, st, 0, st});
        for (int j = 0; j < 40; ++j) {
            const Stress t = j % 4 == 3 ? beyond_apex() : random_stress();
            Stress s = t;
            const MohrResult r = mohr_coulomb_return(mc, strength(mc), s);
            INFO("trial " << t.xx << " " << t.yy << " " << t.xy << " " << t.zz << ", mode " << int(r.mode) << ", phi " << phi << ", c " << c << ", tension " << tens);
            if (r.mode == MohrResult::Elastic) {  // then the trial itself must be admissible
                const Yield f = yield_functions(t, c, phi, tens);
                CHECK(f.fs >= -1e-9 * scale);
                CHECK(f.ft >= -1e-9 * scale);
                ++inside;
                continue;
            }
            edges += r.mode == MohrResult::Edge;
            const Eigen::Vector3d pv = principal(s);
            apex += pv(2) - pv(0) <= 1e-9 * scale;
            const Stress b{t.xx - s.xx, t.yy - s.yy, t.xy - s.xy, t.zz - s.zz};
            const double tol = 1e-9 * compliance_product(mc, b, b) + 1e-12 * scale * scale / m.E;
            for (const Stress& y : ys) {
                const Stress d{y.xx - s.xx, y.yy - s.yy, y.xy - s.xy, y.zz - s.zz};
                CHECK(compliance_product(mc, b, d) <= tol);
            }
        }
    }
    MESSAGE(edges << " returns to an edge, corner or apex, " << apex << " of them to the apex (or the tension corner); " << inside << " trials inside");
    CHECK(edges > 500);
    CHECK(apex > 500);
}

TEST_CASE("flow rule: plastic volume / plastic shear = sin(psi); none with psi = 0") {
    Random rnd(11);
    for (double psi_frac : {0.0, 0.5, 1.0}) {
        int n = 0;
        for (int trial = 0; trial < 2000; ++trial) {
            const double phi = 20 + 20 * rnd.uniform(), psi = psi_frac * phi;
            const Material m = Material::mohr(1, 5e7, 0.3, 1700, phi, 1e4, psi);
            const MaterialConstants k = constants_of(m);
            const Stress s0{-1e4 * rnd.uniform(), -1e4 * rnd.uniform(), 0, -5e3};
            const StrainIncrement d{2e-3 * (rnd.uniform() - 0.5), 2e-3 * (rnd.uniform() - 0.5), 2e-3 * (rnd.uniform() - 0.5), 0};
            Stress s1 = s0;
            elastic_increment(k, d, s1);
            const MohrResult r = mohr_coulomb_return(k, strength(k), s1);
            if (r.mode != MohrResult::Shear) continue;
            ++n;
            const auto vp = plastic_part(m, d, s0, s1);  // independent of the return's own bookkeeping
            // d_eps - C d_sig cancels to ~1e-13 of the increment; the plastic part is >= 1e-3 of it.
            CHECK(std::fabs(vp.first / vp.second - std::sin(psi * kDeg)) < 1e-8);
            // The return's own: (N_psi - 1) / (N_psi + 1) = sin(psi) by construction, to the
            // rounding of a few operations.
            CHECK(std::fabs(r.d_vol_p / r.d_gamma_p - std::sin(psi * kDeg)) < 1e-12);
            CHECK(r.d_gamma_p == approx(vp.second).epsilon(1e-6));
        }
        CHECK(n > 200);
    }
}

TEST_CASE("tension cut-off: sigma3 never exceeds the limit, the apex c/tan(phi) by default") {
    for (double tens : {-1.0, 2000.0}) {
        const Material m = Material::mohr(1, 5e7, 0.3, 1700, 30, 9800, 0, tens);
        const MaterialConstants k = constants_of(m);
        const double limit = tens >= 0 ? tens : 9800 / std::tan(30 * kDeg);
        Stress s{-5e3, -5e3, 0, -5e3};
        double top = -1e300;
        for (int step = 0; step < 300; ++step) {
            elastic_increment(k, {1e-5, 0, 0, 0}, s);  // stretch in x, y held
            mohr_coulomb_return(k, strength(k), s);
            const double s3 = principal(s)(2);
            CHECK(s3 <= limit * (1 + 1e-12));
            top = std::max(top, s3);
        }
        CHECK(top == approx(limit).epsilon(1e-12));
    }
}

TEST_CASE("elastic test: leaving out the tension limit for a stress without tension never changes the decision") {
    // detail::mohr_inside skips the tension planes (and their division) when no principal
    // stress is tensile: exact only because the limit is never negative for c >= 0. Here
    // every decision is compared with the full test (the limit always taken) and, away
    // from the surface, with the independent eigen-solver's yield functions.
    Random r(11);
    long elastic = 0, yielding = 0, skipped = 0;
    for (int k = 0; k < 200000; ++k) {
        const double c = k % 7 == 0 ? 0.0 : 2e4 * r.uniform();
        const double phi = k % 11 == 0 ? 0.0 : 45 * r.uniform();
        const double tens = k % 3 == 0 ? -1.0 : (k % 3 == 1 ? 0.0 : 1e4 * r.uniform());
        const double scale = std::ldexp(1.0, int(r.uniform() * 20) - 4) * 1e3;
        const Stress s{scale * (r.uniform() - 0.8), scale * (r.uniform() - 0.8), scale * (r.uniform() - 0.5), scale * (r.uniform() - 0.8)};
        const double np = detail::flow_number(phi);
        detail::MohrTrial t;
        t.np = np;
        t.two_c_sq = 2 * c * std::sqrt(np);
        const bool inside = detail::mohr_inside(t, tens, s);
        // The full test, as written before the shortcut.
        const double lo = std::min(t.sig[0], t.sig[2]), hi = std::max(t.sig[1], t.sig[2]);
        const double sig_t = detail::tension_limit(np, t.two_c_sq, tens);
        const bool full = lo - hi * np + t.two_c_sq >= 0 && sig_t - hi >= 0;
        REQUIRE(inside == full);
        if (!inside) CHECK(t.sig_t == sig_t);  // the correction reads it
        skipped += hi <= 0 && inside;
        const Yield y = yield_functions(s, c, phi, tens);
        const double margin = 1e-9 * (scale + c);
        if (y.fs > margin && y.ft > margin) { CHECK(inside); ++elastic; }
        if (y.fs < -margin || y.ft < -margin) { CHECK(!inside); ++yielding; }
    }
    // An infinite N_phi (not reachable from a deck, PHI < 90) makes the limit inf / inf:
    // the shortcut must not be taken there.
    for (double c : {0.0, 1e3}) {
        const double np = std::numeric_limits<double>::infinity();
        detail::MohrTrial t;
        t.np = np;
        t.two_c_sq = 2 * c * std::sqrt(np);
        const Stress s{-2e3, -1e3, 0, -1.5e3};
        const bool inside = detail::mohr_inside(t, -1, s);
        const double lo = std::min(t.sig[0], t.sig[2]), hi = std::max(t.sig[1], t.sig[2]);
        CHECK(inside == (lo - hi * np + t.two_c_sq >= 0 && detail::tension_limit(np, t.two_c_sq, -1) - hi >= 0));
    }
    CHECK(skipped > 20000);  // the shortcut was taken
    CHECK(elastic > 20000);
    CHECK(yielding > 20000);
}

#if LPFDM_WIDE
namespace {
// Values where comparisons and arithmetic behave oddly: zeros of both signs, subnormals, huge
// values, infinities, NaN.
const double kOdd[] = {0.0, -0.0, 1e-310, -1e-310, 1e300, -1e300, std::numeric_limits<double>::infinity(),
                       -std::numeric_limits<double>::infinity(), std::numeric_limits<double>::quiet_NaN()};
bool same_bits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }
// Lane l of (xx, yy, xy, zz) holds stress s, bit for bit.
template <class V>
bool lane_holds(const V& xx, const V& yy, const V& xy, const V& zz, int l, const Stress& s) {
    const double lane[4] = {xx[l], yy[l], xy[l], zz[l]}, one[4] = {s.xx, s.yy, s.xy, s.zz};
    return std::memcmp(lane, one, sizeof lane) == 0;
}
// The one-point code's correction of trial s, which mohr_inside found outside (t), with the
// strength strength_of gives a point of N_phi t.np.
MohrResult one_point_correction(const MaterialConstants& mc, const detail::MohrTrial& t, Stress& s) {
    MohrStrength st;
    st.n_phi = t.np;
    st.n_psi = std::min(mc.n_psi, t.np);
    st.tension = mc.tension;
    return detail::mohr_coulomb_correct(mc, st, t, s);
}
// The consult's lanes: four (AVX2, the vector detail::v4d).
template <class V> struct Width;
template <> struct Width<detail::v4d> {
    using Found = detail::MohrLanes;
    static constexpr int N = 4;
    static bool here() { return Simulation::have_wide(); }
};
// Whether this processor runs the lanes of V (says so when it does not).
template <class V>
bool lanes_here() {
    if (!Width<V>::here()) MESSAGE(Width<V>::N << " lanes: not on this processor");
    return Width<V>::here();
}
template <class V>
void settles_as_one_point();
template <class V>
void edges_as_one_point();
}  // namespace
#endif

TEST_CASE("Mohr-Coulomb consult in lanes (AVX2): what it settles, it settles as the one-point code does, bit for bit") {
    // The AVX2 point loop keeps the trials of a group of four that the elastic
    // test in lanes passes (detail::mohr_inside_lanes here), else it makes the closed-form
    // return in lanes (mohr_return_lanes); it keeps a lane that settles and sends any other
    // through mohr_inside and mohr_coulomb_correct. So a lane passed by the first must be exactly
    // one for which mohr_inside takes its first exit; a lane settled as inside must be
    // inside for mohr_inside, a lane returned by shear must get the one-point return's
    // stress and plastic shear exactly (mode Shear), and an unsettled lane must be
    // outside. Random stresses from tiny to huge, with zeros of both signs, subnormals,
    // infinities and NaN in every component and strength, and three tension limits.
#if LPFDM_WIDE
    settles_as_one_point<detail::v4d>();
#else
    MESSAGE("built without the AVX2 version (LPFDM_WIDE): nothing to compare");
#endif
}
#if LPFDM_WIDE
namespace {
template <class V>
void settles_as_one_point() {
    using W = Width<V>;
    constexpr int N = W::N;
    if (!lanes_here<V>()) return;
    Random r(29);
    auto value = [&](double scale, double shift) {
        const int pick = int(r.uniform() * 100);
        return pick < 9 ? kOdd[pick] : scale * (r.uniform() - shift);
    };
    long passed = 0, first_exits = 0, inside = 0, shear = 0, other = 0, past_tension = 0;
    for (int k = 0; k < 240000 / N; ++k) {  // 240 000 trials whatever the width
        Material m = Material::mohr(1, 5e7, 0.1 + 0.35 * r.uniform(), 2000, 45 * r.uniform(), 1e4 * r.uniform());
        m.psi_deg = m.phi_deg * r.uniform();
        m.tension = k % 3 == 0 ? -1.0 : (k % 3 == 1 ? 0.0 : 1e4 * r.uniform());
        const MaterialConstants mc = constants_of(m);
        V xx, yy, xy, zz, np, two_c_sq, d_gamma;
        Stress s[N];
        for (int l = 0; l < N; ++l) {
            const double scale = std::ldexp(1.0, int(r.uniform() * 40) - 20) * 1e3;
            s[l] = {value(scale, 0.8), value(scale, 0.8), value(scale, 0.5), value(scale, 0.8)};
            xx[l] = s[l].xx; yy[l] = s[l].yy; xy[l] = s[l].xy; zz[l] = s[l].zz;
            np[l] = k % 13 == 0 ? value(3, 0) : mc.n_phi * (1 + 0.2 * (r.uniform() - 0.5));  // scattered
            two_c_sq[l] = k % 17 == 0 ? value(1e4, 0.2) : 2 * mc.c * r.uniform() * std::sqrt(np[l]);
        }
        V radius;
        const int first = detail::mohr_inside_lanes(xx, yy, xy, zz, np, two_c_sq, radius);
        typename W::Found found;
        const int bits = detail::mohr_return_lanes(xx, yy, xy, zz, radius, np, two_c_sq, mc.n_psi, mc.tension, mc.a1, mc.a2, d_gamma, found);
        for (int l = 0; l < N; ++l) {
            const double unset = -12345.5;  // mohr_inside sets t.sig_t unless it takes its first exit
            detail::MohrTrial t;
            t.np = np[l];
            t.two_c_sq = two_c_sq[l];
            t.sig_t = unset;
            Stress one = s[l];
            const bool in = detail::mohr_inside(t, mc.tension, one);
            const bool settled = bits >> l & 1, returned = bits >> (N + l) & 1;
            if (first >> l & 1) {  // mohr_inside's first exit: mohr_return_lanes settles it as inside too
                REQUIRE((settled && !returned));
                CHECK(t.sig_t == unset);
                ++passed;
            }
            INFO("stress " << s[l].xx << " " << s[l].yy << " " << s[l].xy << " " << s[l].zz << ", N_phi " << np[l] << ", 2c sqrt(N_phi) " << two_c_sq[l] << ", tension " << mc.tension);
            first_exits += in && t.sig_t == unset;
            if (settled && !returned) {
                ++inside;
                REQUIRE(in);
                CHECK(lane_holds(xx, yy, xy, zz, l, s[l]));
            } else if (returned) {
                ++shear;
                REQUIRE(settled);
                REQUIRE(!in);
                const MohrResult res = one_point_correction(mc, t, one);
                CHECK(res.mode == MohrResult::Shear);
                CHECK(lane_holds(xx, yy, xy, zz, l, one));
                CHECK(same_bits(d_gamma[l], res.d_gamma_p));
                past_tension += t.sig_t - std::max(t.sig[1], t.sig[2]) < 0;  // FLAC's h chose shear
            } else {
                ++other;
                REQUIRE(!in);
            }
        }
    }
    CHECK(passed == first_exits);  // and takes it wherever mohr_inside does
    MESSAGE(N << " lanes: through the first exit " << passed << ", settled as inside " << inside << ", returned by shear " << shear << " (" << past_tension << " of them past the tension limit too), left to the one-point code " << other);
    CHECK(inside > 20000);  // every outcome is frequent
    CHECK(shear > 10000);
    CHECK(past_tension > 1000);
    CHECK(other > 20000);
}
}  // namespace
#endif

TEST_CASE("Mohr-Coulomb edges in lanes (AVX2): the search's first two sets, as the one-point code makes them, bit for bit") {
    // Where FLAC's closed form is not admissible, mohr_coulomb_correct searches sets of
    // planes; detail::mohr_edge_lanes makes its first two (p0 with first[0], then first[1])
    // four lanes at a time. A lane it settles must get the one-point code's mode Edge, its
    // stress and its plastic shear exactly; a lane it leaves is the one-point code's (the
    // closed form's tension return, a later set, or values that are not finite). Trials
    // from the flowing collapse's range (a weak soil near its apex, sig_zz anywhere between
    // and beyond the in-plane pair), then the odd values of the test above.
#if LPFDM_WIDE
    edges_as_one_point<detail::v4d>();
#else
    MESSAGE("built without the AVX2 version (LPFDM_WIDE): nothing to compare");
#endif
}
#if LPFDM_WIDE
namespace {
template <class V>
void edges_as_one_point() {
    using W = Width<V>;
    constexpr int N = W::N;
    if (!lanes_here<V>()) return;
    Random r(31);
    long tried = 0, edge = 0, left = 0, past_shear_only = 0, past_tension = 0, tension_first = 0;
    for (int k = 0; k < 240000 / N; ++k) {  // 240 000 trials whatever the width
        // One trial in five is of a kind where the sort or the branch could slip: a circle of
        // radius 0 (5), sig_zz exactly p - r or p + r (6), N_phi <= 1 under a tension cut-off
        // (7), nu = 0.499 (8), a principal stress exactly at the cut-off (9).
        const int special = k % 25 < 5 ? 5 + k % 25 : 0;
        Material m = Material::mohr(1, 1e7 * (0.5 + r.uniform()), special == 8 ? 0.499 : 0.1 + 0.35 * r.uniform(), 2000, 5 + 40 * r.uniform(), 2000 * r.uniform());
        m.psi_deg = k % 4 == 0 ? m.phi_deg : m.phi_deg * r.uniform();
        m.tension = k % 3 == 0 ? -1.0 : (k % 3 == 1 ? 0.0 : 1e3 * r.uniform());
        if (special == 7 || special == 9) m.tension = 1e3 * r.uniform();
        const MaterialConstants mc = constants_of(m);
        V xx, yy, xy, zz, np, two_c_sq, d_gamma, radius;
        Stress s[N];
        for (int l = 0; l < N; ++l) {
            const double scale = k % 7 == 0 ? std::ldexp(1.0, int(r.uniform() * 40) - 20) * 1e3 : 2e4;
            auto value = [&](double shift) { return k % 11 == 0 && r.uniform() < 0.1 ? kOdd[int(r.uniform() * 9)] : scale * (r.uniform() - shift); };
            s[l] = {value(0.8), value(0.8), value(0.5), value(0.8)};
            if (special == 5) { s[l].yy = s[l].xx; s[l].xy = 0; }
            if (special == 6) {  // as mohr_inside makes p and r
                const double p = 0.5 * (s[l].xx + s[l].yy), a = 0.5 * (s[l].xx - s[l].yy), rr = std::sqrt(a * a + s[l].xy * s[l].xy);
                s[l].zz = l % 2 ? p + rr : p - rr;
            }
            if (special == 9) s[l].zz = m.tension;
            xx[l] = s[l].xx; yy[l] = s[l].yy; xy[l] = s[l].xy; zz[l] = s[l].zz;
            np[l] = special == 7 ? r.uniform() : mc.n_phi * (1 + 0.2 * (r.uniform() - 0.5));  // scattered
            two_c_sq[l] = 2 * mc.c * (r.uniform() < 0.5 ? 0.5 : 1.0) * std::sqrt(np[l]);  // softened or intact
        }
        detail::mohr_inside_lanes(xx, yy, xy, zz, np, two_c_sq, radius);
        typename W::Found found;
        const int bits = detail::mohr_return_lanes(xx, yy, xy, zz, radius, np, two_c_sq, mc.n_psi, mc.tension, mc.a1, mc.a2, d_gamma, found);
        const int unsettled = ~bits & ((1 << N) - 1);
        if (!unsettled) continue;
        const int got = detail::mohr_edge_lanes(xx, yy, xy, zz, radius, np, two_c_sq, mc.n_psi, mc.a1, mc.a2, found, unsettled, d_gamma);
        CHECK((got & ~unsettled) == 0);  // only the lanes it was given
        for (int l = 0; l < N; ++l) {
            if (!(unsettled >> l & 1)) continue;
            ++tried;
            detail::MohrTrial t;
            t.np = np[l];
            t.two_c_sq = two_c_sq[l];
            Stress one = s[l];
            REQUIRE(!detail::mohr_inside(t, mc.tension, one));
            const MohrResult res = one_point_correction(mc, t, one);
            INFO("stress " << s[l].xx << " " << s[l].yy << " " << s[l].xy << " " << s[l].zz << ", N_phi " << np[l] << ", 2c sqrt(N_phi) " << two_c_sq[l] << ", tension " << mc.tension);
            if (!(got >> l & 1)) {  // left: the stress is still the trial
                ++left;
                CHECK(lane_holds(xx, yy, xy, zz, l, s[l]));
                continue;
            }
            ++edge;
            CHECK(res.mode == MohrResult::Edge);
            CHECK(lane_holds(xx, yy, xy, zz, l, one));
            CHECK(same_bits(d_gamma[l], res.d_gamma_p));
            (t.sig_t < std::max(t.sig[1], t.sig[2]) ? past_tension : past_shear_only) += 1;
            tension_first += !found.shear_first[l];  // FLAC's h chose the tension plane (p0 is sig3's)
        }
    }
    MESSAGE(N << " lanes: the closed form left " << tried << ": settled on an edge or the apex line " << edge << " (" << past_shear_only << " past the shear planes only, " << past_tension << " past the tension limit; " << tension_first << " from FLAC's tension return), left to the one-point code " << left);
    CHECK(edge > 20000);  // the lanes settle most of them
    CHECK(past_shear_only > 10000);  // edges of two shear planes
    CHECK(past_tension > 10000);     // the apex line, the corner of tension and shear
    CHECK(tension_first > 200);
    CHECK(left > 1000);  // and leave the rest
}
}  // namespace
#endif

TEST_CASE("Jaumann, eq. 5f: a stressed point turned 360 degrees in small rigid steps keeps its invariants") {
    OnePoint op(Material::mohr(1, 5e7, 0.3, 1700, 30, 9800));
    Points& p = op.sim.points();
    p.sxx[0] = -3e4; p.syy[0] = -1e4; p.sxy[0] = 4e3; p.szz[0] = -1.2e4;  // inside the yield surface
    const Stress s0 = op.stress();
    const Eigen::Vector3d inv0 = principal(s0);
    const int n = 3600;
    const double th = 2 * 3.14159265358979323846 / n;
    for (int k = 0; k < n; ++k) {
        op.strain(0, -th, th, 0);  // du = theta x (x - x_p): no strain, rotation theta
        const Eigen::Vector3d inv = principal(op.stress());
        for (int a = 0; a < 3; ++a) REQUIRE(inv(a) == approx(inv0(a)).epsilon(1e-12));
    }
    // The Cayley rotation turns the material by 2 atan(theta/2) per step, not theta: after
    // n steps it lacks delta = n (theta - 2 atan(theta/2)) (1.6e-6 rad here), and the
    // stress, which turns twice as fast, is off by at most 2 delta times its radius r.
    const Stress s = op.stress();
    const double delta = n * (th - 2 * std::atan(th / 2)), r0 = std::hypot(0.5 * (s0.xx - s0.yy), s0.xy);
    const double tol = 1.01 * 2 * delta * r0;
    CHECK(std::fabs(s.xy - s0.xy) > 0.5 * tol);  // the defect is there, as predicted
    CHECK(std::fabs(s.xx - s0.xx) < tol);
    CHECK(std::fabs(s.yy - s0.yy) < tol);
    CHECK(std::fabs(s.xy - s0.xy) < tol);
    CHECK(s.zz == s0.zz);
    CHECK(p.x[0] == approx(0.5).epsilon(1e-9));
    CHECK(op.sim.points().plastic_shear[0] == 0.0);
}

TEST_CASE("softening: the first yield costs SOFTEN of the cohesion, once") {
    const double c = 9800, phi = 30;
    OnePoint op(Material::mohr(1, 5e7, 0.3, 1700, phi, c, 0, -1, 0.5));
    std::vector<double> tau;
    for (int k = 0; k < 300; ++k) {
        op.strain(1e-5, 0, 0, -1e-5);  // pure shear: p and sigma_zz stay 0, tau grows
        const Stress s = op.stress();
        tau.push_back(std::hypot(0.5 * (s.xx - s.yy), s.xy));
    }
    const double peak = *std::max_element(tau.begin(), tau.end());
    CHECK(peak == approx(c * std::cos(phi * kDeg)).epsilon(1e-12));  // Mohr circle about 0 touching the envelope
    CHECK(tau.back() == approx(0.5 * c * std::cos(phi * kDeg)).epsilon(1e-12));
    CHECK(op.sim.points().yielded[0] == 1);
    CHECK(op.sim.points().plastic_shear[0] > 0);
}

namespace {
double normal_pdf(double z) { return std::exp(-0.5 * z * z) / std::sqrt(2 * 3.14159265358979323846); }
double normal_cdf(double z) { return 0.5 * std::erfc(-z / std::sqrt(2.0)); }
// Mean and standard deviation of N(mu, sd) truncated to [lo, hi].
std::pair<double, double> truncated_moments(double mu, double sd, double lo, double hi) {
    const double a = (lo - mu) / sd, b = (hi - mu) / sd, Z = normal_cdf(b) - normal_cdf(a);
    const double pa = normal_pdf(a), pb = std::isinf(b) ? 0.0 : normal_pdf(b), bpb = std::isinf(b) ? 0.0 : b * pb;
    const double mean = mu + sd * (pa - pb) / Z;
    const double var = sd * sd * (1 + (a * pa - bpb) / Z - std::pow((pa - pb) / Z, 2));
    return {mean, std::sqrt(var)};
}
}  // namespace

TEST_CASE("scatter: c and phi per point are truncated Gaussians with the asked mean and spread, by seed") {
    Scene s;
    s.mx = 160; s.my = 160; s.cell_m = 1;
    s.materials.push_back(Material::mohr(1, 5e7, 0.47, 1700, 28.648, 9800, 0, -1, 0.5, 0.33));
    s.clusters.push_back({1, {0, 0, 160, 160}, 2, {}});
    s.dt_s = 1e-4; s.steps = 1; s.seed = 42;
    Simulation a(s);
    const Points& p = a.points();
    const double n = double(p.size());
    REQUIRE(n > 1e5);
    double sc = 0, sc2 = 0, sp = 0, sp2 = 0;
    for (std::size_t k = 0; k < p.size(); ++k) {
        const double phi = std::asin((p.n_phi[k] - 1) / (p.n_phi[k] + 1)) / kDeg;
        REQUIRE(p.c0[k] >= 0);
        REQUIRE(phi > 0);
        REQUIRE(phi < 90);
        sc += p.c0[k]; sc2 += p.c0[k] * p.c0[k]; sp += phi; sp2 += phi * phi;
    }
    const auto mc = truncated_moments(9800, 0.33 * 9800, 0, INFINITY), mp = truncated_moments(28.648, 0.33 * 28.648, 0, 90);
    const double mean_c = sc / n, sd_c = std::sqrt(sc2 / n - mean_c * mean_c);
    const double mean_p = sp / n, sd_p = std::sqrt(sp2 / n - mean_p * mean_p);
    // Sampling error: 4 standard errors of the mean and of the standard deviation.
    CHECK(std::fabs(mean_c - mc.first) < 4 * mc.second / std::sqrt(n));
    CHECK(std::fabs(sd_c - mc.second) < 4 * mc.second / std::sqrt(2 * n));
    CHECK(std::fabs(mean_p - mp.first) < 4 * mp.second / std::sqrt(n));
    CHECK(std::fabs(sd_p - mp.second) < 4 * mp.second / std::sqrt(2 * n));
    // The same seed gives the same sample; another seed another one.
    Simulation b(s);
    CHECK(b.points().c0 == p.c0);
    CHECK(b.points().n_phi == p.n_phi);
    s.seed = 43;
    Simulation c(s);
    CHECK(c.points().c0 != p.c0);
}

TEST_CASE("the deterministic log and sine agree with the C library to within a few ulp") {
    Random r(3);
    for (int k = 0; k < 100000; ++k) {
        const double x = std::ldexp(r.uniform() + 1e-300, int(r.uniform() * 80) - 60);
        CHECK(detail::log_det(x) == approx(std::log(x)).epsilon(1e-15).scale(1e-300));
        const double a = (r.uniform() - 0.5) * 3.14159265358979323846;
        CHECK(detail::sin_det(a) == approx(std::sin(a)).epsilon(1e-15).scale(1e-300));
    }
    // Known values of the stream (xoshiro256** after splitmix64, seed 1): a change of the
    // generator would silently change every scattered run.
    Random g(1);
    const std::uint64_t first = g.next(), second = g.next();
    Random h(1);
    CHECK(h.next() == first);
    CHECK(h.next() == second);
    CHECK(first != second);
}

TEST_CASE("--profile's Mohr-Coulomb consult counts every Mohr-Coulomb point once a step") {
    // The AVX2 point loop (MOTION CENTRE, the default) consults in blocks and times them
    // when profiling: the count is exactly points x steps (the elastic base's points are
    // not consulted), the time positive; other loops report none; profiling off, none.
    Scene s;
    REQUIRE(read_deck_text("GRID 16 8 0.5\nMATERIAL 1 ELASTIC E=2E7 NU=0.25 RHO=2000\nMATERIAL 2 MOHR E=2E7 NU=0.25 RHO=2000 PHI=30 C=500\n"
                           "CLUSTER 1 0 0 8 1\nCLUSTER 2 0 1 4 3\nFIX XY 0 0 8 0\nFIX X 0 0 0 4\nGRAVITY 0 -9.81\nSTEP 5E-4 30\n",
                           "t.deck", s).empty());
    const long mohr_points = 8 * 4 * 4, steps = 30;
    for (const bool profile : {true, false}) {
        Simulation sim(s);
        sim.set_profiling(profile);
        for (long n = 0; n < steps; ++n) sim.step();
        if (!profile || !Simulation::have_wide()) {
            CHECK(sim.return_updates() == 0);
            continue;
        }
        CHECK(sim.return_updates() == mohr_points * steps);
        CHECK(sim.return_seconds() > 0);
        CHECK(sim.return_seconds() < sim.phase_seconds()[1]);  // a part of the points phase
    }
    Simulation scalar(s, Kernel::Scalar);
    scalar.set_profiling(true);
    for (long n = 0; n < steps; ++n) scalar.step();
    CHECK(scalar.return_updates() == 0);
}
