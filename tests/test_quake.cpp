// Earthquake loading (SHAKE, ABSORB) against known answers: a shear column's free period
// 4H/V_s on a rigid base, a pulse that leaves through a compliant absorbing base, a
// layer's transfer function |1/cos(omega H/V_s)| under a sine sweep; the ground's motion
// integrated from its record (BASELINE: back to rest), the energy account with the ground's
// work and the dashpots' dissipation, and the motion file's errors.
#include <doctest/doctest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <complex>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "../lpfdm.hpp"
#include "common.hpp"

using namespace lpfdm;

namespace {

// One run of a shear-column deck, every step: the top's and the base's velocity in x (the
// middle node of the top row of the material, and the ground), the top's displacement
// relative to the ground, the kinetic energy and the worst |energy_error|.
struct ColumnRun {
    double dt = 0;
    std::vector<double> t, v_top, v_base, rel, ke;
    double worst_error = 0, peak_ke = 0;
    Simulation::Energy last;
};

ColumnRun run_column(const char* deck, int top_row) {
    Scene s;
    const Diagnostics d = read_deck(deck, s);
    REQUIRE(d.empty());
    Simulation sim(s);
    ColumnRun r;
    r.dt = s.dt_s;
    const std::size_t top = std::size_t(sim.node(sim.mx() / 2, top_row));
    double u_top = 0;
    for (long n = 0; n < s.steps; ++n) {
        sim.step();
        u_top += sim.du_x()[top];
        r.t.push_back(sim.time());
        r.v_top.push_back(sim.du_x()[top] / s.dt_s);
        r.v_base.push_back(sim.ground_increment(0) / s.dt_s);
        r.rel.push_back(u_top - sim.ground_displacement(0));
        r.ke.push_back(sim.kinetic_energy());
        r.peak_ke = std::max(r.peak_ke, sim.kinetic_energy());
        if (n % 10 == 9) r.worst_error = std::max(r.worst_error, std::fabs(sim.energy().error));
    }
    r.last = sim.energy();
    return r;
}

// The Fourier transform of x (samples at times t) at frequency f, each sample weighted by w.
std::complex<double> transform(const std::vector<double>& t, const std::vector<double>& x, double f, const std::vector<double>& w = {}) {
    std::complex<double> s = 0;
    for (std::size_t k = 0; k < x.size(); ++k) s += (w.empty() ? 1.0 : w[k]) * x[k] * std::polar(1.0, -2 * kPi * f * t[k]);
    return s;
}

}  // namespace

TEST_CASE("quake: a shear column on a rigid base rings at its free period 4H/V_s after a pulse") {
    const ColumnRun r = run_column("decks/quake_column.deck", 20);
    // After the 0.1 s pulse: the strongest frequency of the top's motion relative to the
    // base (a Hann window over the rest of the run, 3.9 s: about five periods).
    std::vector<double> t, x, w;
    for (std::size_t k = 0; k < r.t.size(); ++k)
        if (r.t[k] > 0.1) { t.push_back(r.t[k]); x.push_back(r.rel[k]); }
    for (std::size_t k = 0; k < t.size(); ++k) w.push_back(0.5 - 0.5 * std::cos(2 * kPi * double(k) / double(t.size() - 1)));
    double best_f = 0, best = 0;
    for (double f = 0.5; f < 3; f += 5e-4) {
        const double a = std::abs(transform(t, x, f, w));
        if (a > best) { best = a; best_f = f; }
    }
    const double period = 1 / best_f, expected = 4 * 20.0 / 100.0;
    MESSAGE("rigid base: free period " << period << " s, 4H/V_s = " << expected << " s (" << 100 * (period / expected - 1) << " %)");
    // The issue asks 3 %; the lattice's dispersion for 20 cells over a quarter wavelength is
    // (k L)^2 / 24 = 2.6e-4, and the scan's step 5e-4 Hz is 0.04 % of 1.25 Hz (half of it at
    // most to the peak): 0.05 % together, and 0.1 % leaves a margin of two. A mass or a
    // modulus off by 1 % moves the period by 0.5 %.
    CHECK(std::fabs(period / expected - 1) < 0.001);
    // Undamped and linear: the energy account closes (the ground's work is the column's
    // energy) but for eq. 12's compensation, second order in the increments.
    MESSAGE("rigid base: worst |energy_error| " << r.worst_error << ", ground work " << r.last.w_ground << " J/m");
    CHECK(r.worst_error < 1e-4);
    CHECK(r.last.w_ground > 0);
}

TEST_CASE("quake: the ground's motion is its record integrated; BASELINE brings it back to rest where it began [slow]") {
    Scene s;
    REQUIRE(read_deck("decks/quake_column.deck", s).empty());
    {  // the pulse: velocity 0.1 sin(pi t / 0.1) m/s, which moves the ground 2 (0.1)(0.1) / pi = 6.37 mm
        Simulation sim(s);
        double peak_v = 0;
        for (long n = 0; n < 100; ++n) {
            sim.step();
            peak_v = std::max(peak_v, sim.ground_increment(0) / s.dt_s);
        }
        // The leapfrog's velocity at half steps of 2 ms samples the sine within 1 - cos(pi 0.01) = 4.9e-4,
        // and the record's 1 ms samples integrated as straight lines add (pi 0.01)^2 / 12 = 8e-5.
        CHECK(std::fabs(peak_v / 0.1 - 1) < 1e-3);
        // Its displacement, the midpoint rule's sum: high by (pi dt / 0.1)^2 / 24 = 1.6e-4, and
        // the velocity of the record's 1 ms samples taken as straight lines low by
        // (pi 0.01)^2 / 12 = 8e-5: +8e-5 expected; the bound is the two errors' sum and more.
        CHECK(std::fabs(sim.ground_displacement(0) / (0.02 / kPi) - 1) < 3e-4);
        // At rest after the pulse: a cosine's samples sum to zero; the record's 8 decimals could
        // leave 101 x 5e-9 m/s^2 x 1 ms = 5e-10 m/s at most, 5e-9 of the peak velocity.
        CHECK(std::fabs(sim.ground_increment(0)) < 1e-6 * 0.1 * s.dt_s);
    }
    // The sweep of quake_sweep.txt starting 0.3 s later: its velocity and displacement drift
    // (the record is not a whole number of cycles); BASELINE ends both at zero, and changes the
    // motion itself little.
    s.shakes[0].file = "quake_sweep.txt";
    Scene with_file;
    REQUIRE(read_deck("decks/quake_layer.deck", with_file).empty());
    s.shakes[0].t = with_file.shakes[0].t;
    s.shakes[0].a = with_file.shakes[0].a;
    s.shakes[0].start = 0.3;
    s.steps = 10300;  // to the record's end
    double peak[2] = {0, 0}, end_d[2] = {0, 0}, end_v[2] = {0, 0};
    for (const int baseline : {0, 1}) {
        s.shakes[0].baseline = baseline;
        Simulation sim(s);
        for (long n = 0; n < s.steps; ++n) {
            sim.step();
            if (n < 150) REQUIRE(sim.ground_increment(0) == 0.0);  // nothing before START
            peak[baseline] = std::max(peak[baseline], std::fabs(sim.ground_displacement(0)));
        }
        end_d[baseline] = sim.ground_displacement(0);
        end_v[baseline] = sim.ground_increment(0) / s.dt_s;
    }
    MESSAGE("sweep: ground displacement at the end " << end_d[0] << " m, velocity " << end_v[0] << " m/s; with BASELINE " << end_d[1] << ", " << end_v[1]
                                                     << "; largest displacement " << peak[0] << " and " << peak[1] << " m");
    CHECK(std::fabs(end_d[0]) > 1e-3);
    // Rounding over 10 300 steps: half an ulp of a velocity of 0.16 m/s at most (1.4e-17) a
    // step, 1.4e-13 m/s, 1.4e-12 m once integrated over the 20 s; of a motion of 4-8 cm.
    CHECK(std::fabs(end_d[1]) < 1e-10);
    CHECK(std::fabs(end_v[1]) < 1e-10);
    // The trend BASELINE takes off is small against the record (peak 0.5 m/s^2): the drift
    // it removes (8 cm by the end) builds up from a tiny offset over 20 s.
    double c0, c1;
    detail::baseline_trend(s.shakes[0], s.dt_s, c0, c1);
    MESSAGE("sweep: BASELINE's trend c0 = " << c0 << " m/s^2, c1 = " << c1 << " m/s^3");
    CHECK(std::fabs(c0) + std::fabs(c1) * 20 < 1e-2 * 0.5);
}

TEST_CASE("quake: a pulse through a compliant absorbing base leaves the column after one reflection") {
    const ColumnRun r = run_column("decks/quake_column_compliant.deck", 40);
    // Up 0.4 s, down 0.4 s, the pulse 0.1 s long: from 1.1 s on the wave has left.
    double worst_after = 0;
    for (std::size_t k = 0; k < r.t.size(); ++k)
        if (r.t[k] >= 1.1) worst_after = std::max(worst_after, r.ke[k]);
    MESSAGE("compliant base: kinetic energy after 1.1 s at most " << 100 * worst_after / r.peak_ke << " % of its peak " << r.peak_ke
                                                                   << " J/m; worst |energy_error| " << r.worst_error);
    CHECK(worst_after <= 0.05 * r.peak_ke);
    CHECK(r.worst_error < 1e-4);
    // What the ground put in, the dashpots took out. What is left is what the base reflects:
    // a dashpot on the lattice's edge node (half mass) reflects (k L)^2 / 16 of a wave, so
    // (k L)^4 / 256 of its energy, 0.3 % at 15 Hz where the pulse's spectrum has its first zero.
    MESSAGE("compliant base: the dashpots took " << r.last.d_absorb << " J/m of the ground's " << r.last.w_ground << " J/m");
    CHECK(std::fabs(r.last.d_absorb / r.last.w_ground - 1) < 0.01);
}

TEST_CASE("quake: a layer's transfer function under a sine sweep is |1 / cos(omega H / V_s)| up to the third mode [slow]") {
    const ColumnRun r = run_column("decks/quake_layer.deck", 20);
    // Closed form with local damping alpha taken as a damping ratio D = alpha / pi (a complex
    // shear modulus G (1 + 2iD), V_s* = V_s sqrt(1 + 2iD)): |1 / cos(omega H / V_s*)|.
    const double H = 20, Vs = 100, D = 0.1 / kPi;
    auto closed_form = [&](double f) {
        const std::complex<double> vs = Vs * std::sqrt(std::complex<double>(1, 2 * D));
        return 1 / std::abs(std::cos(2 * kPi * f * H / vs));
    };
    // The spectra of the top's and the base's velocity every 0.01 Hz; the transfer function
    // in bands of +-0.15 Hz, sqrt(sum |V_top|^2 / sum |V_base|^2) (a single frequency's ratio
    // scatters by +-25 % at 1/30 Hz resolution), and the closed form weighted alike.
    std::vector<double> f, top2, base2, form2;
    for (double x = 0.4; x < 7.9; x += 0.01) {
        f.push_back(x);
        top2.push_back(std::norm(transform(r.t, r.v_top, x)));
        base2.push_back(std::norm(transform(r.t, r.v_base, x)));
        form2.push_back(closed_form(x) * closed_form(x) * base2.back());
    }
    auto band = [&](double at, double& measured, double& expected) {
        double st = 0, sb = 0, sf = 0;
        for (std::size_t k = 0; k < f.size(); ++k)
            if (std::fabs(f[k] - at) <= 0.15 + 1e-9) { st += top2[k]; sb += base2[k]; sf += form2[k]; }
        measured = std::sqrt(st / sb);
        expected = std::sqrt(sf / sb);
    };
    for (int n = 1; n <= 3; ++n) {
        // The resonance: the unsmoothed ratio's largest value within 20 % of f_n.
        const double fn = (2 * n - 1) * Vs / (4 * H);
        double best_f = 0, best = 0, peak = 0, peak_form = 0;
        for (double x = 0.8 * fn; x < 1.2 * fn; x += 0.002) {
            const double a = std::abs(transform(r.t, r.v_top, x)) / std::abs(transform(r.t, r.v_base, x));
            if (a > best) { best = a; best_f = x; }
        }
        for (double x = 0.9 * fn; x < 1.1 * fn; x += 0.05) {
            double m, e;
            band(x, m, e);
            peak = std::max(peak, m);
            peak_form = std::max(peak_form, e);
        }
        const double trough_at = n * Vs / (2 * H);
        double trough, trough_form;
        band(trough_at, trough, trough_form);
        MESSAGE("mode " << n << ": resonance at " << best_f << " Hz ((2n - 1) V_s / 4H = " << fn << "); smoothed peak " << peak << " (closed form "
                        << peak_form << "); at " << trough_at << " Hz " << trough << " (" << trough_form << ")");
        // The ratio scatters from one frequency to the next, so its largest value may lie
        // anywhere near the top of the resonance, whose half width at half power is D f_n
        // = 3.2 % of f_n; the lattice's dispersion, (k L)^2 / 24 = 0.6 % at the third mode, is below it.
        CHECK(std::fabs(best_f / fn - 1) < 0.03);
        // At n V_s / 2H the layer passes the base's motion nearly unchanged: the damping's whole
        // effect there is 1 - 1 / cosh(n alpha), 4.4 % at the third trough. This checks the
        // elastic layer's trough, not the damping (the peaks below do).
        CHECK(std::fabs(trough / trough_form - 1) < 0.05);
        // The peaks' heights depend on how local damping (not viscous) acts on one mode:
        // alpha / pi is its damping ratio in steady vibration only. A peak's height is
        // proportional to 1 / D (1 / sinh((2n - 1) alpha / 2) for this layer): 15 % is an
        // effective damping ratio within 15 % of alpha / pi.
        CHECK(std::fabs(peak / peak_form - 1) < 0.15);
    }
}

namespace {

// The points within 1 m of the slope's crest (6 m, 6 m) of decks/quake_slope.deck, and
// their mean displacement since `from` (positions, x then y).
struct Crest {
    std::vector<std::size_t> ids;
    std::vector<double> from;
    explicit Crest(const Simulation& sim) {
        const Points& p = sim.points();
        for (std::size_t k = 0; k < p.size(); ++k)
            if (std::hypot(p.x[k] - 6, p.y[k] - 6) < 1.0) ids.push_back(k);
        mark(sim);
    }
    void mark(const Simulation& sim) {
        from.clear();
        for (const std::size_t k : ids) { from.push_back(sim.points().x[k]); from.push_back(sim.points().y[k]); }
    }
    void moved(const Simulation& sim, double& dx, double& dy) const {
        dx = dy = 0;
        for (std::size_t a = 0; a < ids.size(); ++a) { dx += sim.points().x[ids[a]] - from[2 * a]; dy += sim.points().y[ids[a]] - from[2 * a + 1]; }
        dx /= double(ids.size()); dy /= double(ids.size());
    }
};

}  // namespace

namespace {
// The largest |work in - stored - dissipated| of a run, every 10 steps, over the largest
// |w_ground| (the account's residual as a fraction of the ground's work); slip gets the
// last d_slip over the largest |w_ground|.
double ground_account(Scene s, double& slip) {
    Simulation sim(s);
    double worst = 0, ground = 0;
    for (long n = 1; n <= s.steps; ++n) {
        sim.step();
        if (n % 10 != 0 && n != s.steps) continue;
        const Simulation::Energy e = sim.energy();
        const double in = e.w_walls + e.w_fixes + e.w_ground, stored = e.kinetic + e.strain + e.gravity;
        const double out = e.d_damping + e.d_plastic + e.d_absorb + e.d_slip;
        worst = std::max(worst, std::fabs(in - stored - out));
        ground = std::max(ground, std::fabs(e.w_ground));
    }
    REQUIRE(ground > 0);
    slip = sim.energy().d_slip / ground;
    return worst / ground;
}

// The deck's scene under MAPPING SMOOTH and ADVECT FLIP, without its outputs.
Scene flip_deck(const char* deck) {
    Scene s;
    REQUIRE(read_deck(deck, s).empty());
    s.mapping = Mapping::Smooth;
    s.advect = Advect::Flip;
    s.outputs.clear();
    REQUIRE(validate(s).empty());
    return s;
}
}  // namespace

// ADVECT FLIP with SHAKE (the rigid base's pulse, quake_column.deck) and with ABSORB (the
// compliant base, quake_column_compliant.deck), at the decks' L and at L / 2 (--refine 2):
// the account closes to 0.5 % of the ground's work (its remainder, the transfer's loss
// at second order, sum_n M_n a_n^2 - sum_p m_p g_p^2, falls with L; measured 4.7e-4 and
// 4.7e-5 on the rigid base, 1e-6 on the compliant one) once it names the slip at the
// shaken nodes (flip_slip: the ground's change starts from the ground's own increment,
// the material beside it moves otherwise). Without d_slip the rigid base's account
// missed 1.78 % and 0.45 %: the slip, which falls as L^2 and not with dt (it is the
// weights' reach, not the steps), and is 0 where no support changes speed (the compliant
// base's nodes are free: its dashpots' work is counted on the increments the points bring
// back, absorb_work; on eq. 13's it missed 0.63 % and 0.13 %).
TEST_CASE("quake: ADVECT FLIP takes SHAKE and ABSORB; its account closes to 0.5 % of the ground's work, the slip at the shaken nodes named [slow]") {
    for (const char* deck : {"decks/quake_column.deck", "decks/quake_column_compliant.deck"}) {
        Scene s = flip_deck(deck);
        const bool rigid = std::string(deck) == "decks/quake_column.deck";
        double slip_coarse, slip_fine;
        const double coarse = ground_account(s, slip_coarse);
        refine(s, 2);
        const double fine = ground_account(s, slip_fine);
        MESSAGE(std::string(deck) << " with ADVECT FLIP: the account's residual " << 100 * coarse << " % of the ground's work, " << 100 * fine
                                  << " % at L / 2; the slip " << 100 * slip_coarse << " % and " << 100 * slip_fine << " %");
        CHECK(coarse < 0.005);
        CHECK(fine < 0.005);
        if (rigid) {
            CHECK(fine < coarse);                       // the remainder falls with L
            CHECK(slip_coarse > 0.01);                  // the mechanism is there, and it is the slip ...
            CHECK(slip_fine / slip_coarse > 0.25 / 1.2);  // ... falling as L^2 (4 times, within 20 %)
            CHECK(slip_fine / slip_coarse < 0.25 * 1.2);
        }
    }
}

// The two other shaken decks that run in seconds, under ADVECT FLIP: the layer shaken at its
// base through 30 s (damped, elastic) and the slope shaken past its yield (Mohr-Coulomb,
// local damping, the burst from 2 s on): the account within 0.5 % of the ground's work
// (measured 1.1e-5 and 1.1e-3; the paper's mapping 1.1e-6 and 5.2e-3), and below half of
// the slip it names (0.26 % and 0.49 %): unnamed, the slip would be the residual. (quake_cliff.deck's
// collapse frees twenty times the ground's work from gravity: its account is a fraction of
// that, tests/README.)
TEST_CASE("quake: ADVECT FLIP's account on the shaken layer and slope decks closes to 0.5 % of the ground's work [slow]") {
    for (const char* deck : {"decks/quake_layer.deck", "decks/quake_slope.deck"}) {
        Scene s = flip_deck(deck);
        double slip;
        const double residual = ground_account(s, slip);
        MESSAGE(std::string(deck) << " with ADVECT FLIP: the account's residual " << 100 * residual << " % of the ground's work, the slip " << 100 * slip << " %");
        CHECK(residual < 0.005);
        CHECK(residual < 0.5 * slip);
    }
}

TEST_CASE("quake: a dry slope shaken past its yield acceleration moves as Newmark's sliding block estimates [slow]") {
    Scene deck;
    REQUIRE(read_deck("decks/quake_slope.deck", deck).empty());
    deck.outputs.clear();
    deck.reorder = 0;  // the crest's points are found by their storage place
    // The yield acceleration, pseudo-statically: a horizontal body force k g toward the
    // face; the slope fails where its crest still moves more than 5 mm between 2 s and 4 s
    // of damped steps (below it, it comes to rest within the first 2 s). Bisection to 0.005 g.
    auto fails = [&](double k) {
        Scene s = deck;
        s.shakes.clear();
        s.gravity_x = k * 9.81;
        s.steps = 8000;
        Simulation sim(s);
        Crest crest(sim);
        for (long n = 0; n < 4000; ++n) sim.step();
        crest.mark(sim);
        for (long n = 4000; n < s.steps; ++n) sim.step();
        double dx, dy;
        crest.moved(sim, dx, dy);
        return dx > 0.005;
    };
    double lo = 0, hi = 0.64;
    while (hi - lo > 0.005) (fails(0.5 * (lo + hi)) ? hi : lo) = 0.5 * (lo + hi);
    const double ky = 0.5 * (lo + hi), ay = ky * 9.81;
    // Newmark: a rigid block yielding at a_y, sliding toward the face (+x) while the ground
    // accelerates away from it (-x) by more than a_y, until its relative velocity is zero
    // again; the record as the deck gives it (0.4 g, 2 Hz), integrated every 0.1 ms.
    const Shake& k = deck.shakes[0];
    double v = 0, newmark = 0;
    const double h = 1e-4;
    for (long n = 0; n * h < 6; ++n) {
        const double t = n * h;
        double ag = 0;
        if (t <= k.t.back()) {
            const std::size_t i = std::min(std::size_t(std::upper_bound(k.t.begin(), k.t.end(), t) - k.t.begin()) - 1, k.t.size() - 2);
            ag = k.scale * (k.a[i] + (t - k.t[i]) / (k.t[i + 1] - k.t[i]) * (k.a[i + 1] - k.a[i]));
        }
        const double rel = -ag - ay;
        if (v > 0 || rel > 0) v = std::max(0.0, v + rel * h);
        newmark += v * h;
    }
    // The deck's run: the crest's displacement from START to the end, relative to the
    // ground (BASELINE brings the ground back to where it was).
    auto shaken = [&](double scale, double& dx, double& dy) {
        Scene s = deck;
        s.shakes[0].scale = scale;
        Simulation sim(s);
        Crest crest(sim);
        const long start = long(std::ceil(k.start / s.dt_s - 1e-9));
        for (long n = 0; n < s.steps; ++n) {
            if (n == start) crest.mark(sim);
            sim.step();
        }
        crest.moved(sim, dx, dy);
        dx -= sim.ground_displacement(0);
        CHECK(std::fabs(sim.ground_displacement(0)) < 1e-9);  // rounding over 8000 steps of a motion of 2.5 cm
    };
    double dx, dy, qx, qy;
    shaken(1.0, dx, dy);
    shaken(0.375, qx, qy);  // 0.15 g: below a_y, even amplified 1.4 times
    const double moved = std::hypot(dx, dy);
    MESSAGE("slope: yield acceleration " << ky << " g; 0.4 g burst: crest moved " << moved << " m (dx " << dx << ", dy " << dy << "), Newmark "
                                         << newmark << " m, ratio " << moved / newmark << "; 0.15 g burst: " << std::hypot(qx, qy) << " m (Newmark 0)");
    // Pseudo-statically the slope holds under 0.2 g and fails under 0.3 g: c / gamma H =
    // 0.085 at 45 degrees with phi = 30 has a factor of safety near 1.5 at rest.
    CHECK(ky > 0.15);
    CHECK(ky < 0.35);
    REQUIRE(newmark > 0.01);
    // Newmark's block is rigid: it takes the base's acceleration, where the slope amplifies
    // it (first frequency V_s / 4H = 98 / 24 = 4.1 Hz against the burst's 2 Hz: about 1.4
    // times at the crest), and the sliding mass is not one block. The continuum moves
    // more, within a factor of three (the usual spread between the two).
    CHECK(moved > newmark);
    CHECK(moved < 3 * newmark);
    CHECK(dx > 0);   // toward the face
    CHECK(dy < 0);   // and down
    // Below a_y nothing slides: what the crest moves is elastic and settles (under 1 cm).
    CHECK(std::hypot(qx, qy) < 0.01);
    CHECK(std::hypot(qx, qy) < 0.1 * moved);
}

namespace {

// A deck text read as if it were decks/NAME (its motion files beside it): the diagnostics.
Diagnostics read_in_decks(const std::string& text, Scene& s) { return read_deck_text(text, "decks/inline.deck", s); }

}  // namespace

TEST_CASE("quake: ABSORB RIGHT lets a P wave leave a bar that a free end would send back") {
    // A bar 60 m long, every node held vertically (one-dimensional compression), pushed at
    // its left end by the pulse: the wave travels at c_p = sqrt(M / rho) = 173 m/s and
    // reaches the right end at 0.35 s; by 0.6 s it has gone through it, or come back.
    const std::string bar = "GRID 60 2 1.0\nMATERIAL 1 ELASTIC E=5E7 NU=0.25 RHO=2000\nCLUSTER 1 0 0 60 2\nFIX Y 0 0 60 2\nFIX X 0 0 0 2\n"
                            "SHAKE X FILE=quake_pulse.txt\nSTEP 2E-3 500\n";
    // What the bar holds at the end (kinetic and strain energy) against what the ground put
    // in: all of it with a free end (undamped, the account closes to 1e-6), almost none
    // through the dashpots.
    auto kept = [&](const Scene& s) {
        Simulation sim(s);
        for (long n = 0; n < s.steps; ++n) sim.step();
        const Simulation::Energy e = sim.energy();
        return (e.kinetic + e.strain) / e.w_ground;
    };
    Scene open, absorbing;
    REQUIRE(read_in_decks(bar, open).empty());
    REQUIRE(read_in_decks(bar + "ABSORB RIGHT\n", absorbing).empty());
    const double held_open = kept(open), held_absorbing = kept(absorbing);
    MESSAGE("P wave: energy left in the bar at 1 s " << 100 * held_absorbing << " % of the ground's work with ABSORB RIGHT, " << 100 * held_open
                                                     << " % with a free end");
    CHECK(held_absorbing < 0.02);
    CHECK(held_open > 0.99);
}

TEST_CASE("quake: an absorbing edge released at START keeps a column at rest under gravity") {
    // Brought to rest by damping 0.8 with fixed sides and base; at START = 4 s the edges
    // absorb, their nodes free, each keeping the reaction it had; SCALE=0: no shaking, and no
    // damping from then on. The column must not move: its top moves less than 1e-4 of its
    // settlement (left fixed, it moves under 0.5 um: what settling remains at 4 s).
    const std::string deck = "GRID 4 10 1.0\nMATERIAL 1 ELASTIC E=2E7 NU=0.25 RHO=2000\nCLUSTER 1 0 0 4 10\nFIX X 0 0 0 10\nFIX X 4 0 4 10\n"
                             "FIX XY 0 0 4 0\nGRAVITY 0 -9.81\nDAMPING 0.8\nSHAKE X FILE=quake_pulse.txt SCALE=0 START=4 DAMPING=0\n"
                             "ABSORB BOTTOM LEFT RIGHT\nSTEP 1E-3 5000\n";
    Scene s;
    REQUIRE(read_in_decks(deck, s).empty());
    Simulation sim(s);
    const Points& p = sim.points();
    std::size_t top = 0;
    for (std::size_t k = 0; k < p.size(); ++k) if (p.y[k] > p.y[top]) top = k;
    const double y0 = p.y[top];
    double at_start = 0, worst = 0, error_at_start = 0;
    for (long n = 0; n < s.steps; ++n) {
        if (n == 4000) { at_start = p.y[top]; error_at_start = sim.energy().error; }
        sim.step();
        if (n >= 4000) worst = std::max(worst, std::fabs(p.y[top] - at_start));
    }
    const double settlement = y0 - at_start;
    MESSAGE("released at rest: top moved " << worst << " m after START, settlement " << settlement << " m; held reactions' work " << sim.energy().w_fixes);
    CHECK(settlement > 0);
    CHECK(worst < 1e-4 * settlement);
    // The account closes to the order of the strain (the column settled under damping before
    // START): rho g H / M = 8.2e-3 at the base (test_energy.cpp's ringing column, at 0.98 %,
    // reads 0.5 %).
    CHECK(std::fabs(sim.energy().error) < 8e-3);
    // The release itself: from START on nothing moves (the top within 1e-4 of its settlement),
    // so no term of the account can change by more than the work of such a motion, 1e-4 of
    // the settling's.
    MESSAGE("energy_error at START " << error_at_start << ", at the end " << sim.energy().error);
    CHECK(std::fabs(sim.energy().error - error_at_start) < 1e-4);
}

TEST_CASE("quake: the motion file's problems are reported at its own line and column") {
    const OwnDir own("quake_motion");
    const std::string& dir = own.path;
    auto motion = [&](const std::string& name, const std::string& text) {
        std::ofstream(dir + "/" + name) << text;
    };
    const std::string deck = "GRID 4 4 1\nMATERIAL 1 ELASTIC E=5E7 NU=0.3 RHO=2000\nCLUSTER 1 0 0 4 2\nFIX XY 0 0 4 0\nSTEP 1E-4 10\n";
    auto first = [&](const std::string& card) {
        Scene s;
        const Diagnostics d = read_deck_text(deck + card + "\n", dir + "/t.deck", s);
        return d.empty() ? std::string("no error") : d[0].str();
    };
    motion("empty.txt", "");
    motion("comments.txt", "# nothing but\n\n# comments\n");
    motion("one.txt", "0 1\n");
    motion("word.txt", "0 0\n0.1 abc\n");
    motion("three.txt", "0 0\n0.1 1 2\n");
    motion("back.txt", "0 0\n0.2 1\n0.1 2\n");
    motion("same.txt", "0 0\n0.1 1\n0.1 2\n");
    motion("negative.txt", "-0.1 0\n0.1 1\n");
    motion("nan.txt", "0 0\n0.1 nan\n");
    motion("good.txt", "# t a\n0, 0\n0.1, 1   # a comment\n\n0.2 0\n");
    motion("crlf.txt", "\xEF\xBB\xBF# a byte order mark, CR LF\r\n0 0\r\n0.1 1\r\n0.2 0\r\n");
    motion("cr.txt", "# old Mac line ends\r0 0\r0.1 1\r0.2 0\r");
    CHECK(first("SHAKE X FILE=nowhere.txt") == dir + "/t.deck:6:14: error: cannot open the motion file '" + dir + "/nowhere.txt': No such file or directory (a relative FILE= is read from the deck's directory)");
    CHECK(first("SHAKE X FILE=empty.txt") == dir + "/empty.txt:1:1: error: the motion file holds no samples (two numbers a line: time [s], acceleration [m/s^2])");
    CHECK(first("SHAKE X FILE=comments.txt") == dir + "/comments.txt:1:1: error: the motion file holds no samples (two numbers a line: time [s], acceleration [m/s^2])");
    CHECK(first("SHAKE X FILE=one.txt") == dir + "/one.txt:1:1: error: the motion file holds one sample; a record needs at least two");
    CHECK(first("SHAKE X FILE=word.txt") == dir + "/word.txt:2:5: error: acceleration: expected a finite number, found 'abc'");
    CHECK(first("SHAKE X FILE=three.txt") == dir + "/three.txt:2:7: error: expected two numbers, time [s] and acceleration [m/s^2]; this line has 3");
    CHECK(first("SHAKE X FILE=back.txt") == dir + "/back.txt:3:1: error: time 0.1 s does not come after the line before's 0.2 s: times must increase");
    CHECK(first("SHAKE X FILE=same.txt") == dir + "/same.txt:3:1: error: time 0.1 s does not come after the line before's 0.1 s: times must increase");
    CHECK(first("SHAKE X FILE=negative.txt") == dir + "/negative.txt:1:1: error: time -0.1 s is before 0: the record starts at time 0 or later");
    CHECK(first("SHAKE X FILE=nan.txt") == dir + "/nan.txt:2:5: error: acceleration: expected a finite number, found 'nan'");
    CHECK(first("SHAKE X FILE=.") .find("cannot read the motion file '" + dir + "/.': it is a directory") != std::string::npos);
    CHECK(first("SHAKE X FILE=/dev/zero").find("cannot read the motion file '/dev/zero': it is not a regular file") != std::string::npos);
    CHECK(first("SHAKE X FILE=good.txt") == "no error");
    for (const char* name : {"crlf.txt", "cr.txt"}) {
        Scene t;
        REQUIRE(read_deck_text(deck + "SHAKE X FILE=" + name + "\n", dir + "/t.deck", t).empty());
        CHECK(t.shakes[0].t == std::vector<double>{0, 0.1, 0.2});
        CHECK(t.shakes[0].a == std::vector<double>{0, 1, 0});
    }
    Scene s;
    REQUIRE(read_deck_text(deck + "SHAKE Y FILE=good.txt SCALE=2\n", dir + "/t.deck", s).empty());
    REQUIRE(s.shakes.size() == 1);
    CHECK(s.shakes[0].dir == kFixY);
    CHECK(s.shakes[0].t == std::vector<double>{0, 0.1, 0.2});
    CHECK(s.shakes[0].a == std::vector<double>{0, 1, 0});
    CHECK(s.shakes[0].scale == 2.0);
}

TEST_CASE("quake: SHAKE and ABSORB cards: every mistake named where it is") {
    const std::string deck = "GRID 4 4 1\nMATERIAL 1 ELASTIC E=5E7 NU=0.3 RHO=2000\nCLUSTER 1 0 0 4 2\nFIX XY 0 0 4 0\nSTEP 1E-4 10\n";
    auto errors = [&](const std::string& cards) {
        Scene s;
        const Diagnostics d = read_in_decks(deck + cards, s);
        std::string all;
        for (const Diagnostic& x : d) all += x.str() + "\n";
        return all;
    };
    CHECK(errors("SHAKE Z FILE=quake_pulse.txt\n") == "decks/inline.deck:6:7: error: unknown direction 'Z' (X or Y) (did you mean X?)\n");
    CHECK(errors("SHAKE X FILE=quake_pulse.txt SCALING=2\n") ==
          "decks/inline.deck:6:30: error: unknown parameter 'SCALING' (this card takes FILE, SCALE, START, DAMPING)\n");
    CHECK(errors("SHAKE X FILE=quake_pulse.txt COMPLIANT COMPLIANT\n") == "decks/inline.deck:6:40: error: COMPLIANT given twice\n");
    CHECK(errors("SHAKE X FILE=quake_pulse.txt BASLINE\n") == "decks/inline.deck:6:30: error: unknown word 'BASLINE' (COMPLIANT or BASELINE) (did you mean BASELINE?)\n");
    CHECK(errors("SHAKE X SCALE=2\n") == "decks/inline.deck:6:16: error: missing parameter FILE= (the motion file: time [s] and acceleration [m/s^2] a line)\n");
    CHECK(errors("SHAKE X FILE=quake_pulse.txt START=-1\n").find("decks/inline.deck:6:36: error: START must") == 0);
    CHECK(errors("SHAKE X FILE=quake_pulse.txt DAMPING=1\n").find("decks/inline.deck:6:38: error: SHAKE DAMPING must") == 0);
    CHECK(errors("SHAKE X FILE=quake_pulse.txt SCALE=x\n") == "decks/inline.deck:6:36: error: SCALE: expected a number, found 'x'\n");
    CHECK(errors("SHAKE X FILE=quake_pulse.txt\nSHAKE X FILE=quake_pulse.txt\n").find("decks/inline.deck:7:1: error: the ground is shaken in X twice (SHAKE at line 6)") == 0);
    CHECK(errors("SHAKE X FILE=quake_pulse.txt\nSHAKE Y FILE=quake_pulse.txt START=1\n").find("decks/inline.deck:7:1: error: the SHAKE cards must agree on START") == 0);
    CHECK(errors("SHAKE Y FILE=quake_pulse.txt COMPLIANT\n").empty());
    // A lone '=' where a word or a parameter belongs (the fuzzer's find: a null token).
    CHECK(errors("SHAKE X = 3\n") == "decks/inline.deck:6:7: error: missing field: X or Y\n");  // read as X=3
    CHECK(errors("SHAKE X FILE=quake_pulse.txt COMPLIANT =\n") == "decks/inline.deck:6:40: error: missing value after COMPLIANT=\n");
    CHECK(errors("SHAKE X FILE=quake_pulse.txt =\n") == "decks/inline.deck:6:30: error: '=' without a parameter name\n");
    CHECK(errors("ABSORB BOTTOM SIDEWAYS\n") == "decks/inline.deck:6:15: error: unknown edge 'SIDEWAYS' (BOTTOM, TOP, LEFT or RIGHT)\n");
    CHECK(errors("ABSORB BOTTOM\nABSORB LEFT BOTTOM\n") == "decks/inline.deck:7:1: error: ABSORB BOTTOM is given twice\n");
    CHECK(errors("ABSORB\n") == "decks/inline.deck:6:7: error: missing field: BOTTOM, TOP, LEFT or RIGHT\n");
    Scene s;
    REQUIRE(read_in_decks(deck + "FIX X 0 0 0 4\nSHAKE X FILE=quake_pulse.txt\n", s).empty());
    s.fixes.erase(s.fixes.begin(), s.fixes.end());  // nothing held in X: nothing to move
    const Diagnostics v = validate(s);
    REQUIRE(v.size() == 1);
    CHECK(v[0].message.find("SHAKE X moves the nodes fixed in X, and no FIX card holds that direction") == 0);
    // A record BASELINE would integrate over more than 1e8 steps is refused (set-up time),
    // and the warning's own integration stays bounded whatever the run's length.
    Scene huge;
    REQUIRE(read_in_decks(deck + "SHAKE X FILE=quake_pulse.txt BASELINE\n", huge).empty());
    huge.shakes[0].t.back() = 1e6;
    huge.steps = 1000000000;
    const Diagnostics h = validate(huge);
    REQUIRE(h.size() == 1);
    CHECK(h[0].message == "the motion record lasts 1e+06 s, 1e+10 steps of dt: BASELINE integrates at most 1e8 (shorten the record's quiet end, or take a larger dt)");
    huge.shakes[0].baseline = false;
    CHECK(validate(huge).empty());
    const auto t0 = std::chrono::steady_clock::now();
    (void)warnings(huge);
    CHECK(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() < 5.0);  // 1e6 coarse steps at most, not 1e9
    // START beyond 1e15 steps (its step number would overflow), a wall on an absorbing edge.
    CHECK(errors("SHAKE X FILE=quake_pulse.txt START=1E300\n").find("decks/inline.deck:6:1: error: START is more than 1e15 time steps away") == 0);
    CHECK(errors("WALL 1 1 2 3 2 0 -0.1\nABSORB TOP LEFT\n").empty());
    CHECK(errors("WALL 1 0 1 0 2 0.1 0\nABSORB TOP LEFT\n").find("decks/inline.deck:6:1: error: the wall starts on an edge of the lattice that ABSORB makes absorbing (line 7)") == 0);
    // --set reaches SHAKE cards by their order.
    Scene t;
    REQUIRE(read_in_decks(deck + "SHAKE X FILE=quake_pulse.txt\n", t).empty());
    CHECK(apply_setting(t, "SHAKE1.SCALE", 0.5).empty());
    CHECK(t.shakes[0].scale == 0.5);
    CHECK(apply_setting(t, "SHAKE2.SCALE", 0.5) == "there is no SHAKE number 2 (cards of a kind count from 1)");
}

TEST_CASE("quake: a warning when the ground moves more than a quarter cell (the lattice does not follow it)") {
    // A record of constant acceleration 0.1 m/s^2 for 10 s, a run of 4 s: the ground moves
    // 0.1 (4)^2 / 2 = 0.8 m, 0.8 of a cell. BASELINE takes the whole record off (a constant
    // is a trend): no motion, no warning.
    const OwnDir own("quake_motion");
    const std::string& dir = own.path;
    std::ofstream(dir + "/drift.txt") << "0 0.1\n10 0.1\n";
    const std::string deck = "GRID 8 20 1.0\nMATERIAL 1 ELASTIC E=5E7 NU=0.25 RHO=2000\nCLUSTER 1 2 0 6 20\nFIX XY 0 0 8 0\nSTEP 2E-3 2000\n";
    for (const bool baseline : {false, true}) {
        Scene s;
        REQUIRE(read_deck_text(deck + "SHAKE X FILE=drift.txt" + (baseline ? " BASELINE" : "") + "\n", dir + "/t.deck", s).empty());
        const Diagnostics w = warnings(s);
        if (baseline) {
            CHECK(w.empty());
            continue;
        }
        REQUIRE(w.size() == 1);
        CHECK(w[0].pos.line == 6);
        CHECK(w[0].message == "the ground moves up to 0.8 m in this run, 0.8 cells: the lattice stays put, so points may leave at its edges (BASELINE takes off the record's drift)");
        // and the run's ground goes there
        Simulation sim(s);
        for (long n = 0; n < s.steps; ++n) sim.step();
        // The midpoint rule integrates a constant acceleration exactly: rounding of 2000 steps.
        CHECK(std::fabs(sim.ground_displacement(0) / 0.8 - 1) < 1e-9);
    }
}

TEST_CASE("quake: with a rigid base, side dashpots act on the motion relative to the ground [slow]") {
    // A stiff layer (V_s = 1000 m/s: first frequency V_s / 4H = 50 Hz) on a rigid base
    // shaken by the 2 Hz burst moves with the base as a rigid body. Side dashpots against
    // the ground at rest resisted that rigid motion (force 2 rho c_p H v against the
    // layer's inertia rho W H a: about three times it here); acting on the motion relative
    // to the ground, they leave it alone: the centre moves as with free sides within 1 %,
    // and they take out less than 1 % of the layer's largest kinetic energy (the ground's
    // net work on a body that ends at rest where it began is only what its elastic
    // vibration keeps or loses).
    const std::string layer = "GRID 40 5 1.0\nMATERIAL 1 ELASTIC E=5E9 NU=0.25 RHO=2000\nCLUSTER 1 0 0 40 5\nFIX XY 0 0 40 0\n"
                              "SHAKE X FILE=quake_burst.txt BASELINE\nSTEP 2E-4 15000\n";
    double peak_ke = 0;
    auto centre = [&](const std::string& extra, Simulation::Energy& e) {
        Scene s;
        REQUIRE(read_in_decks(layer + extra, s).empty());
        Simulation sim(s);
        const std::size_t top = std::size_t(sim.node(20, 5));
        double u = 0, peak = 0;
        for (long n = 0; n < s.steps; ++n) {
            sim.step();
            u += sim.du_x()[top];
            peak = std::max(peak, std::fabs(u));
            peak_ke = std::max(peak_ke, sim.kinetic_energy());
        }
        e = sim.energy();
        return peak;
    };
    Simulation::Energy e_free, e_abs;
    const double free_sides = centre("", e_free), absorbing = centre("ABSORB LEFT RIGHT\n", e_abs);
    MESSAGE("stiff layer: the centre's largest displacement " << absorbing << " m with ABSORB LEFT RIGHT, " << free_sides << " m with free sides; dashpots took "
                                                             << e_abs.d_absorb << " J/m, the layer's largest kinetic energy " << peak_ke << " J/m");
    // The dashpots see only the layer's motion relative to its base, quasi-static at 2 Hz against
    // 50 Hz: (2 / 50)^2 = 0.16 % of the base's; they cannot change the centre's by more.
    CHECK(std::fabs(absorbing / free_sides - 1) < 0.01);
    CHECK(e_abs.d_absorb < 0.01 * peak_ke);
    // Elastic and undamped: the account closes to the layer's strain (rho a H / G = 2e-5 at
    // 0.4 g) and the leapfrog's (omega dt)^2 = 6e-6 at 2 Hz; a dashpot work off by half would show.
    CHECK(std::fabs(e_abs.error) < 1e-4);
}

TEST_CASE("quake: a long record costs its samples once, not once a step") {
    // 100 000 samples (100 s at 1 ms) with BASELINE and a short run: the record's cursor
    // moves forward with the time asked; scanning from the first sample every step took 96 s.
    const OwnDir own("quake_motion");
    const std::string& dir = own.path;
    {
        std::ofstream f(dir + "/long.txt");
        for (int k = 0; k <= 100000; ++k) f << k * 1e-3 << " " << std::sin(k * 1e-3 * 2 * kPi) << "\n";
    }
    Scene s;
    REQUIRE(read_deck_text("GRID 4 4 1\nMATERIAL 1 ELASTIC E=5E7 NU=0.3 RHO=2000\nCLUSTER 1 0 0 4 2\nFIX XY 0 0 4 0\nSHAKE X FILE=long.txt BASELINE\nSTEP 1E-4 10\n",
                           dir + "/t.deck", s).empty());
    const auto t0 = std::chrono::steady_clock::now();
    (void)warnings(s);
    Simulation sim(s);  // BASELINE: 1e6 steps of the record
    for (long n = 0; n < s.steps; ++n) sim.step();
    const double took = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    MESSAGE("long record: set-up and 10 steps in " << took << " s");
    CHECK(took < 5.0);
}
