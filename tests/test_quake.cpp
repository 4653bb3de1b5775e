// Earthquake loading (SHAKE, ABSORB) against known answers: a shear column's free period
// 4H/V_s on a rigid base, a pulse that leaves through a compliant absorbing base, a
// layer's transfer function |1/cos(omega H/V_s)| under a sine sweep; the ground's motion
// integrated from its record (BASELINE: back to rest), the energy account with the ground's
// work and the dashpots' dissipation, and the motion file's errors.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdio>
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
    // (k L)^2 / 24 = 2.6e-4, and the scan's step 5e-4 Hz is 0.04 % of 1.25 Hz.
    CHECK(std::fabs(period / expected - 1) < 0.005);
    // Undamped and linear: the energy account closes (the ground's work is the column's
    // energy) but for eq. 12's compensation, second order in the increments.
    MESSAGE("rigid base: worst |energy_error| " << r.worst_error << ", ground work " << r.last.w_ground << " J/m");
    CHECK(r.worst_error < 1e-4);
    CHECK(r.last.w_ground > 0);
    CHECK(r.last.d_absorb == 0.0);
}

TEST_CASE("quake: the ground's motion is its record integrated; BASELINE brings it back to rest where it began") {
    Scene s;
    REQUIRE(read_deck("decks/quake_column.deck", s).empty());
    {  // the pulse: velocity 0.1 sin(pi t / 0.1) m/s, which moves the ground 2 (0.1)(0.1) / pi = 6.37 mm
        Simulation sim(s);
        double peak_v = 0;
        for (long n = 0; n < 100; ++n) {
            sim.step();
            peak_v = std::max(peak_v, sim.ground_increment(0) / s.dt_s);
        }
        // The leapfrog's velocity at half steps of 2 ms samples the sine within 1 - cos(pi 0.01) = 5e-4.
        CHECK(std::fabs(peak_v / 0.1 - 1) < 1e-3);
        // Its displacement, the midpoint rule's sum: within (pi dt / 0.1)^2 / 24 = 1.6e-4 (and the samples' 1 ms).
        CHECK(std::fabs(sim.ground_displacement(0) / (0.02 / kPi) - 1) < 2e-3);
        CHECK(std::fabs(sim.ground_increment(0)) < 1e-6 * 0.1 * s.dt_s);  // at rest after the pulse (a cosine's samples sum to zero)
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
    CHECK(std::fabs(end_d[1]) < 1e-10);  // of a motion of 4-8 cm: rounding over 10 300 steps
    CHECK(std::fabs(end_v[1]) < 1e-10);
    CHECK(std::fabs(peak[1] / peak[0] - 1) < 0.5);
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
    // What the ground put in, the dashpots took out (what is left is the little above).
    MESSAGE("compliant base: the dashpots took " << r.last.d_absorb << " J/m of the ground's " << r.last.w_ground << " J/m");
    CHECK(std::fabs(r.last.d_absorb / r.last.w_ground - 1) < 0.01);
}

TEST_CASE("quake: a layer's transfer function under a sine sweep is |1 / cos(omega H / V_s)| up to the third mode") {
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
        CHECK(std::fabs(best_f / fn - 1) < 0.03);  // the tolerance; the lattice's dispersion is below 1 % here
        // At n V_s / 2H the layer passes the base's motion unchanged whatever the damping.
        CHECK(std::fabs(trough / trough_form - 1) < 0.05);
        // The peaks' heights depend on how local damping (not viscous) acts on one mode:
        // alpha / pi is its damping ratio in steady vibration only.
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
        CHECK(std::fabs(sim.ground_displacement(0)) < 1e-9);
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
