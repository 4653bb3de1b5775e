// Hard numerical cases: each scene runs long enough to show trouble and
// asserts finite values, the exact mass balance, and energy that never grows without a
// source. What each case measured is printed (doctest MESSAGE, shown with -s).
//
// Energy. Kinetic energy is nodal at half steps, stresses at whole steps, so KE + strain
// energy is not what the leapfrog conserves; its shadow energy is:
//   E_n = 1/2 sum_nodes m du(n-1/2) . du(n+1/2) / dt^2 + W(sigma_n) + potential(x_n),
// exactly constant for a linear elastic lattice at any stable step. It is what these
// tests watch (Shadow below). W is the complementary energy of the point stresses
// (plane strain, sigma_zz carried), the potential is - sum m g . x over the points.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <string>
#include <vector>

#include "../lpfdm.hpp"
#include "common.hpp"

using namespace lpfdm;

namespace {

Scene elastic_scene(int mx, int my, double L, Box block, int ppc = 2, double nu = 0.25) {
    Scene s;
    s.mx = mx; s.my = my; s.cell_m = L;
    s.materials.push_back(Material::elastic(1, 2e7, nu, 2000));
    s.clusters.push_back({1, block, ppc, {}});
    s.dt_s = 1; s.steps = 1;
    return s;
}

// Elastic energy stored in the points (their complementary energy).
double strain_energy(const Simulation& sim) {
    const Points& p = sim.points();
    double w = 0;
    for (std::size_t k = 0; k < p.size(); ++k) {
        const Material& m = *sim.scene().material(sim.material_id(k));
        const double a = p.sxx[k], b = p.syy[k], c = p.szz[k], t = p.sxy[k];
        w += p.vol[k] * (a * a + b * b + c * c - 2 * m.nu * (a * b + b * c + c * a) + 2 * (1 + m.nu) * t * t) / (2 * m.E);
    }
    return w;
}

double potential_energy(const Simulation& sim) {
    const Points& p = sim.points();
    double e = 0;
    for (std::size_t k = 0; k < p.size(); ++k) e -= sim.point_mass(k) * (sim.scene().gravity_x * p.x[k] + sim.scene().gravity_y * p.y[k]);
    return e;
}

bool nodes_finite(Simulation& sim) {
    for (std::size_t q = 0; q < sim.du_x().size(); ++q)
        if (!std::isfinite(sim.du_x()[q]) || !std::isfinite(sim.du_y()[q])) return false;
    return true;
}
bool finite(Simulation& sim) { return sim.healthy() && sim.first_nonfinite_point() == -1 && nodes_finite(sim); }
bool mass_exact(const Simulation& sim) { return sim.mass_inside() + sim.mass_outflow() == sim.mass_initial(); }

// Whether every value stayed finite and the mass balance exact, checked after each step.
struct Health {
    bool ok = true, mass = true;
    void check(Simulation& sim) {
        ok &= finite(sim);
        mass &= mass_exact(sim);
    }
};

// Steps a simulation and measures the shadow energy after each step; checked() also
// checks its health.
struct Shadow : Health {
    std::vector<double> px, py;
    double first = 0, max = -1e300, min = 1e300, last = 0;
    long n = 0;
    double step(Simulation& sim) {
        px.assign(sim.du_x().begin(), sim.du_x().end());
        py.assign(sim.du_y().begin(), sim.du_y().end());
        sim.step();
        double k = 0;
        const auto& m = sim.node_mass();
        for (std::size_t q = 0; q < px.size(); ++q) k += 0.5 * m[q] * (px[q] * sim.du_x()[q] + py[q] * sim.du_y()[q]);
        const double dt = sim.scene().dt_s;
        last = k / (dt * dt) + strain_energy(sim) + potential_energy(sim);
        if (n++ == 0) first = last;
        max = std::max(max, last);
        min = std::min(min, last);
        return last;
    }
    void checked(Simulation& sim) {
        step(sim);
        check(sim);
    }
    void run(Simulation& sim, long steps) {  // stops at the first non-finite value
        for (long k = 0; k < steps && ok; ++k) checked(sim);
    }
};


// One step at rest (so that every node knows its mass), then the field f(x, y) -> (ux, uy)
// as the nodal increments of every node with mass.
template <class F>
void set_increments(Simulation& sim, F f) {
    sim.step();
    const double L = sim.cell_size();
    for (int j = 0; j <= sim.my(); ++j)
        for (int i = 0; i <= sim.mx(); ++i) {
            const std::size_t n = std::size_t(sim.node(i, j));
            if (sim.node_mass()[n] == 0) continue;
            double ux = 0, uy = 0;
            f(i, j, i * L, j * L, ux, uy);
            sim.du_x()[n] = ux;
            sim.du_y()[n] = uy;
        }
}

// Random nodal increments of up to 5e-7 m per direction (the same sequence every time):
// they excite every mode the lattice has, the fastest included.
void shake(Simulation& sim) {
    Random r{2024};
    set_increments(sim, [&](int, int, double, double, double& ux, double& uy) {
        ux = 5e-7 * (2 * r.uniform() - 1);
        uy = 5e-7 * (2 * r.uniform() - 1);
    });
}

// Mass-weighted centroid of the points.
void centroid(const Simulation& sim, double& cx, double& cy) {
    const Points& p = sim.points();
    double m = 0;
    cx = cy = 0;
    for (std::size_t k = 0; k < p.size(); ++k) { cx += sim.point_mass(k) * p.x[k]; cy += sim.point_mass(k) * p.y[k]; m += sim.point_mass(k); }
    cx /= m; cy /= m;
}

}  // namespace

// ------------------------------------------------------------------ time step ---

TEST_CASE("hard: 10^5 undamped steps at 0.9 of the stable limit keep values finite, mass exact, energy from growing [slow]") {
    // A free elastic block (6 x 6 cells, 2 x 2 points each) shaken by random nodal
    // increments of 10^-6 L, which excite every mode the lattice has, the fastest included.
    Scene s = elastic_scene(10, 10, 0.5, {1, 1, 4, 4});
    s.dt_s = 0.9 * stable_dt(s);
    REQUIRE(validate(s).empty());
    Simulation sim(s);
    shake(sim);
    Shadow e;
    const long n = 100000;
    double first_window = 0, last_window = 0;  // max of KE + W over the first and last 10 %
    for (long k = 0; k < n && e.ok; ++k) {
        e.checked(sim);
        const double raw = sim.kinetic_energy() + strain_energy(sim);
        if (k < n / 10) first_window = std::max(first_window, raw);
        if (k >= n - n / 10) last_window = std::max(last_window, raw);
    }
    MESSAGE("0.9 of the limit, 10^5 steps: shadow energy " << e.first << " J/m at the start, at most " << e.max << ", at the end " << e.last
                                                          << "; max KE + W over the last 10 % / the first 10 %: " << last_window / first_window);
    CHECK(e.ok);
    CHECK(e.mass);
    CHECK(sim.mass_outflow() == 0);
    CHECK(e.max <= e.first * (1 + 1e-9));       // never above the start
    CHECK(last_window <= first_window * 1.01);  // and no slow growth of the raw energy
}

TEST_CASE("hard: ADVECT POINTS at 0.9 of the stable limit: 2 x 10^4 undamped steps, energy never above the start [slow]") {
    // The same shaken block with the increments carried by the points. Measured over 10^5
    // steps: the shadow energy never rose; it fell to 0.052 of its start within the first
    // 2 x 10^4 steps and then stayed (eq. 12 keeps it all): the transfer averages away
    // part of a non-affine increment field.
    Scene s = elastic_scene(10, 10, 0.5, {1, 1, 4, 4});
    s.dt_s = 0.9 * stable_dt(s);
    s.advect = Advect::Points;
    s.motion = Motion::Centre;
    REQUIRE(validate(s).empty());
    Simulation sim(s);
    shake(sim);
    Shadow e;
    e.run(sim, 20000);
    MESSAGE("ADVECT POINTS, 0.9 of the limit: shadow energy " << e.first << " J/m at the start, at most " << e.max << ", at the end " << e.last);
    CHECK(e.ok);
    CHECK(e.mass);
    CHECK(e.max <= e.first * (1 + 1e-9));
    CHECK(e.last < e.first);
}

TEST_CASE("hard: a step above the stable limit is refused with both numbers, and 1.1 of the limit does diverge") {
    Scene s = elastic_scene(10, 10, 0.5, {1, 1, 4, 4});
    const double lim = stable_dt(s);
    s.dt_s = 1.1 * lim;
    const Diagnostics d = validate(s);
    REQUIRE(d.size() == 1);
    CHECK(d[0].message.find("above the stable limit") != std::string::npos);
    char a[32], b[32];
    std::snprintf(a, sizeof a, "%.6g", s.dt_s);
    std::snprintf(b, sizeof b, "%.6g", lim);
    CHECK(d[0].message.find(a) != std::string::npos);
    CHECK(d[0].message.find(b) != std::string::npos);
    s.dt_s = 0.9 * lim;
    CHECK(validate(s).empty());
    // The refusal is not over-cautious: run anyway at 1.1, a lone cell (the mode the limit
    // is set by) blows up.
    s = elastic_scene(6, 6, 0.5, {1, 1, 1.5, 1.5});
    s.dt_s = 1.1 * stable_dt(s);
    Simulation sim(s);
    shake(sim);
    sim.step();
    const double ke0 = sim.kinetic_energy();
    long bad = -1;  // the step at which the energy passed a million times its start
    for (long k = 0; k < 20000 && bad < 0; ++k) {
        sim.step();
        if (!sim.healthy() || !(sim.kinetic_energy() < 1e6 * ke0)) bad = k;
    }
    MESSAGE("at 1.1 of the limit the shaken lone cell's energy grew a millionfold by step " << bad);
    CHECK(bad >= 0);
}

// Finding: local damping (eq. 14) makes the fastest mode see (1 + alpha) times its
// stiffness: its force opposes du every step, so D adds alpha |F| to it. The lattice is
// then stable only for dt <= L / c_p / sqrt(1 + alpha): measured with the confined column
// (decks/column.deck at nu = 0.25) stable at 0.80 / unstable at 0.83 of L/c_p for alpha =
// 0.5 (1/sqrt(1.5) = 0.816), 0.90 / 0.93 for alpha = 0.2 (0.913), 0.74 / 0.75 for alpha =
// 0.8 (0.745). stable_dt() now includes the damping (it once accepted up to L / c_p, and a
// damped deck at 0.75-1.0 of that blew up within 50 steps).
TEST_CASE("hard: 0.9 of the stable limit with local damping 0.8 stays bounded") {
    Scene s;
    REQUIRE(read_deck("decks/column.deck", s).empty());
    s.dt_s = 0.9 * stable_dt(s);
    REQUIRE(validate(s).empty());
    Simulation sim(s);
    long bad = -1;
    for (long k = 0; k < 3000 && bad < 0; ++k) {
        sim.step();
        if (!sim.healthy()) bad = k;
    }
    MESSAGE("damped column at 0.9 of the accepted limit: unhealthy at step " << bad);
    CHECK(bad == -1);
}

// Finding: stable_dt() is the limit of the lattice's interior (the fastest interior mode
// is an alternating stretch with omega = 2 c_p / L). A cell whose four nodes belong to it
// alone (a lone cell of material, a corner) also has a uniform dilation mode with
// omega^2 = 4 (M + lambda) / (rho L^2), M = K + 4G/3, lambda = K - 2G/3: the element bound
// of the one-point cell with lumped masses. Its limit is L sqrt(rho / (M + lambda)) =
// sqrt(1 - nu) L / c_p: 0.866 at nu = 0.25, 0.714 at 0.49. A shaken lone cell at 0.9
// (nu = 0.25) gains 10^10 times its energy in 5000 steps (stable at 0.85); at nu = 0.49
// it is stable at 0.7 and blows up at 0.9. Lone cells are common in flows (trapdoor,
// debris of a cliff). stable_dt() now uses this bound, and / sqrt(1 + alpha) with damping.
TEST_CASE("hard: 0.9 of the stable limit stays bounded for a lone cell of material") {
    for (double nu : {0.25, 0.49}) {
        Scene s = elastic_scene(6, 6, 0.5, {1, 1, 1.5, 1.5}, 2, nu);
        s.dt_s = 0.9 * stable_dt(s);
        REQUIRE(validate(s).empty());
        Simulation sim(s);
        shake(sim);
        Shadow e;
        bool ok = true;
        for (long k = 0; k < 5000 && ok; ++k) { e.step(sim); ok = finite(sim); }
        MESSAGE("lone cell, nu = " << nu << ": healthy " << ok << ", shadow energy at most " << e.max / e.first << " of the start");
        CHECK(ok);
        CHECK(e.max <= e.first * (1 + 1e-4));  // conserved but for eq. 12's second-order terms; unstable, it grows 1e10-fold
    }
}

// ------------------------------------------------------ near incompressibility ---

TEST_CASE("hard: nearly incompressible column under gravity, nu = 0.49 and 0.499: no locking, no blow-up [slow]") {
    // decks/column.deck (confined, damped) with a higher Poisson ratio; the step at 0.67 of
    // stable_dt() (below the damped limit 0.745, see above). Reference: sigma_yy = -rho g
    // (H - y), sigma_xx = nu / (1 - nu) sigma_yy, settlement gamma H^2 / 2M.
    for (double nu : {0.25, 0.49, 0.499}) {
        Scene s;
        REQUIRE(read_deck("decks/column.deck", s).empty());
        s.materials[0].nu = nu;
        s.dt_s = 0.67 * stable_dt(s);
        REQUIRE(validate(s).empty());
        Simulation sim(s);
        const Points& p = sim.points();
        const std::vector<double> y0(p.y.begin(), p.y.end());
        Shadow e;
        e.run(sim, 8000);
        const Material& m = s.materials[0];
        const double H = 12, gamma = m.rho * 9.81, M = m.E * (1 - nu) / ((1 + nu) * (1 - 2 * nu));
        double num = 0, numx = 0, den = 0, top_err = 0, top_ref = 0;
        for (std::size_t k = 0; k < p.size(); ++k) {
            const double yref = y0[std::size_t(p.id[k])], ref = -gamma * (H - yref);
            num += std::pow(p.syy[k] - ref, 2);
            numx += std::pow(p.sxx[k] - nu / (1 - nu) * ref, 2);
            den += ref * ref;
            if (yref > H - 0.5 * s.cell_m) {
                const double u = gamma / M * (H * yref - 0.5 * yref * yref);
                top_err += std::fabs((yref - p.y[k]) - u);
                top_ref += u;
            }
        }
        const double syy = std::sqrt(num / den), sxx = std::sqrt(numx / den), settle = top_err / top_ref;
        MESSAGE("nu = " << nu << ", dt " << s.dt_s << " s: sigma_yy L2 error " << syy << ", sigma_xx " << sxx << " (of |sigma_yy|), settlement "
                        << settle << "; unbalanced force ratio " << sim.unbalanced_ratio() << "; energy max - start " << e.max - e.first << " J/m");
        CHECK(e.ok);
        CHECK(e.mass);
        CHECK(syy < 0.025);
        CHECK(sxx < 0.025);
        CHECK(settle < 0.01);
        CHECK(sim.unbalanced_ratio() < 1e-5);  // at rest
        CHECK(e.max <= e.first + 1e-9 * std::fabs(e.first));  // gravity only releases energy; damping takes it
    }
}

// --------------------------------------------------------------- stiff cap ---

TEST_CASE("hard: a cap 1000 times stiffer than the soil below it [slow]") {
    // Confined column: 8 m of soil (E = 2e7) under 1 m of cap (E = 2e10), rough base,
    // smooth sides, damping 0.8; the step at 0.9 of the cap's limit (damping included),
    // 31.6 times below the soil's. Reference sigma_yy = -rho g (9 - y) through both.
    auto run = [](double stiffness, double& soil_err, double& cap_err, double& unbal, double& grow) {
        Scene s;
        s.mx = 4; s.my = 22; s.cell_m = 0.5;
        s.materials.push_back(Material::elastic(1, 2e7, 0.3, 2000));
        s.materials.push_back(Material::elastic(2, 2e7 * stiffness, 0.3, 2000));
        s.clusters.push_back({1, {0, 0, 2, 8}, 2, {}});
        s.clusters.push_back({2, {0, 8, 2, 9}, 2, {}});
        s.fixes.push_back({kFixX, {0, 0, 0, 11}, {}});
        s.fixes.push_back({kFixX, {2, 0, 2, 11}, {}});
        s.fixes.push_back({kFixX | kFixY, {0, 0, 2, 0}, {}});
        s.gravity_y = -9.81; s.damping = 0.8; s.dt_s = 1; s.steps = 40000;
        s.dt_s = 0.9 * stable_dt(s);
        REQUIRE(validate(s).empty());
        Simulation sim(s);
        const Points& p = sim.points();
        const std::vector<double> y0(p.y.begin(), p.y.end());
        Shadow e;
        e.run(sim, s.steps);
        CHECK(e.ok);
        CHECK(e.mass);
        double num = 0, den = 0;
        cap_err = 0;
        for (std::size_t k = 0; k < p.size(); ++k) {
            const double yref = y0[std::size_t(p.id[k])], ref = -2000 * 9.81 * (9 - yref);
            if (sim.material_id(k) == 1) { num += std::pow(p.syy[k] - ref, 2); den += ref * ref; }
            else cap_err = std::max(cap_err, std::fabs(p.syy[k] - ref) / (2000 * 9.81 * 1.0));
        }
        soil_err = std::sqrt(num / den);
        unbal = sim.unbalanced_ratio();
        grow = e.max - e.first;
    };
    double soil1, cap1, unbal1, grow1, soil, cap, unbal, grow;
    run(1, soil1, cap1, unbal1, grow1);
    run(1000, soil, cap, unbal, grow);
    MESSAGE("cap 1000 x stiffer: soil sigma_yy L2 error " << soil << " (uniform column " << soil1 << "), cap error up to " << cap
                                                          << " of its own weight per area, unbalanced ratio " << unbal << ", energy max - start " << grow);
    CHECK(soil < 0.03);
    CHECK(soil == approx(soil1).epsilon(0.02));  // the stiff cap costs no accuracy below it
    CHECK(cap < 0.25);
    CHECK(unbal < 1e-6);
    CHECK(grow <= 0);
}

// ---------------------------------------------------------------- impact ---

namespace {

struct Drop {
    double rebound = 0;   // highest centroid after the first contact, over the starting one (from the contact height)
    double energy = 0;    // largest shadow energy over the starting one, as a fraction of the energy of the drop
    double peak_stress = 0, impact_stress = 0;  // largest -sigma_yy, rho c_p v at contact
    bool ok = true, mass = true, through = false;
};

// A 1 m x 1 m elastic block (4K x 4K cells, 2 x 2 points each) dropped from h onto a
// rough fixed floor, no damping, for 1.6 s, dt = frac of the limit.
Drop drop(double h, double frac, int K = 1, Advect advect = Advect::Eq12, Motion motion = Motion::Paper) {
    Scene s = elastic_scene(40 * K, 24 * K, 0.25 / K, {4.5, h, 5.5, h + 1});
    s.advect = advect;
    s.motion = motion;
    s.fixes.push_back({kFixX | kFixY, {0, 0, 10, 0}, {}});
    s.gravity_y = -9.81;
    s.dt_s = frac * stable_dt(s);
    Simulation sim(s);
    const Points& p = sim.points();
    Drop d;
    double cx, cy0, cy, cy_prev, cy_min = 1e300;
    centroid(sim, cx, cy0);
    cy_prev = cy0;
    bool contact = false;
    Shadow e;
    for (long n = 0; n < long(1.6 / s.dt_s); ++n) {
        e.checked(sim);
        if (!e.ok) break;
        centroid(sim, cx, cy);
        double ymin = 1e300;
        for (std::size_t k = 0; k < p.size(); ++k) { ymin = std::min(ymin, p.y[k]); d.peak_stress = std::max(d.peak_stress, -p.syy[k]); }
        if (!contact && ymin < s.cell_m) {
            contact = true;
            d.impact_stress = 2000 * s.materials[0].p_wave_speed() * (cy_prev - cy) / s.dt_s;
        }
        cy_min = std::min(cy_min, cy);
        if (contact && cy > cy_min) d.rebound = std::max(d.rebound, cy);
        cy_prev = cy;
    }
    d.ok = e.ok;
    d.mass = e.mass;
    d.through = sim.mass_outflow() > 0;
    d.rebound = (d.rebound - 0.5) / (cy0 - 0.5);
    d.energy = (e.max - e.first) / (2000 * 9.81 * h);
    return d;
}

}  // namespace

TEST_CASE("hard: a block dropped 0.5 m onto a fixed floor bounces, no higher than it fell") {
    const Drop d = drop(0.5, 0.5);
    MESSAGE("drop 0.5 m: rebound to " << d.rebound << " of the drop height; shadow energy up to " << d.energy
                                       << " of the drop energy above the start during the impact; peak stress " << d.peak_stress
                                       << " Pa = " << d.peak_stress / d.impact_stress << " rho c_p v");
    CHECK(d.ok);
    CHECK(d.mass);
    CHECK_FALSE(d.through);       // nothing passes the floor or leaves
    CHECK(d.rebound > 0.5);       // it bounces ...
    CHECK(d.rebound < 1.0);       // ... and does not gain height
}

// From higher up, a block only 4 cells across bounces above its start: the 2 m drop
// rebounds to 1.27 of its height at dt = 0.1 of the limit (1.21 at 0.5), and the shadow
// energy rises by 0.34 of the drop energy. The cause is resolution, not an instability:
// the excess falls under refinement and the rebound goes below one from 8 cells across on
// (measured at dt 0.1 / 0.5 of the limit, L = 0.25, 0.125, 0.0625 m: rebound 1.27 / 1.21,
// 0.87 / 0.87, 0.83 / 0.78; energy excess 0.34 / 0.27, 0.035 / 0.026, 0.015 / 0.011).
// A trace at L = 0.25 m shows when: through the contact itself the shadow energy holds to
// 0.5 %; the excess comes after, in flight, with the block ringing, in jumps as its rows
// of stressed points cross cell edges (+4.8 kJ/m as the bottom row leaves the floor's
// cells, +2.7 as it crosses the third edge; 39 kJ/m is the drop energy). Carrying the
// increments on the points (ADVECT POINTS) does not remove it (rebound 1.18 at 4 cells
// across, 0.89 at 8), so it is not only the mass moving between nodes that eq. 12 leaves.
TEST_CASE("hard: a block dropped 2 m bounces no higher than it fell once 8 cells span it; the energy excess falls with L [slow]") {
    const Drop a = drop(2.0, 0.5, 1), b = drop(2.0, 0.5, 2), c = drop(2.0, 0.5, 4);
    for (const Drop* d : {&a, &b, &c})
        MESSAGE("drop 2 m, L = " << (d == &a ? 0.25 : d == &b ? 0.125 : 0.0625) << " m, dt 0.5 of the limit: rebound to " << d->rebound
                                 << " of the drop height; shadow energy up to " << d->energy << " of the drop energy above the start");
    for (const Drop* d : {&a, &b, &c}) {
        CHECK(d->ok);
        CHECK(d->mass);
        CHECK_FALSE(d->through);
    }
    CHECK(b.rebound < 1.0);
    CHECK(c.rebound < 1.0);
    // A discretisation error: at least first order in L (each halving at most 0.6 of it).
    CHECK(b.energy < 0.6 * a.energy);
    CHECK(c.energy < 0.6 * b.energy);
    CHECK(c.energy < 0.02);
}

// ------------------------------------------------------------- rigid spin ---

namespace {

struct Spin {
    double angle = 0, pos_err = 0, dist_err = 0, stress = 0, centripetal = 0, energy_gain = 0, energy_end = 0;
    bool ok = true, mass = true;
};

// A stress-free 2 m x 1 m block (8 x 4 cells of L/K, 2 x 2 points) given the increments of
// a rigid rotation about its centre, 90 degrees in 2 s, no gravity, no damping.
Spin spin(int K, Advect advect = Advect::Eq12, Motion motion = Motion::Paper) {
    Scene s = elastic_scene(16 * K, 16 * K, 0.25 / K, {1, 1.5, 3, 2.5});
    s.advect = advect;
    s.motion = motion;
    s.dt_s = 1e-3 / K;
    const long n = 2000L * K;
    const double w = (kPi / 2) / double(n);  // radians per step
    Simulation sim(s);
    const Points& p = sim.points();
    const std::vector<double> x0(p.x.begin(), p.x.end()), y0(p.y.begin(), p.y.end());
    set_increments(sim, [&](int, int, double x, double y, double& ux, double& uy) { ux = -w * (y - 2); uy = w * (x - 2); });
    Shadow e;
    Spin r;
    for (long k = 0; k < n; ++k) {
        e.checked(sim);
        for (std::size_t q = 0; q < p.size(); ++q) r.stress = std::max({r.stress, std::fabs(p.sxx[q]), std::fabs(p.syy[q]), std::fabs(p.sxy[q])});
    }
    r.ok = e.ok;
    r.mass = e.mass;
    double cx, cy;
    centroid(sim, cx, cy);
    double sxx = 0, syy = 0, sxy = 0;
    for (std::size_t q = 0; q < p.size(); ++q) {
        const std::size_t id = std::size_t(p.id[q]);
        r.pos_err = std::max(r.pos_err, std::hypot(p.x[q] - (cx - (y0[id] - 2)), p.y[q] - (cy + (x0[id] - 2))));
        sxx += (p.x[q] - cx) * (p.x[q] - cx); syy += (p.y[q] - cy) * (p.y[q] - cy); sxy += (p.x[q] - cx) * (p.y[q] - cy);
        for (std::size_t o = q + 1; o < p.size(); ++o) {
            const std::size_t io = std::size_t(p.id[o]);
            const double d0 = std::hypot(x0[id] - x0[io], y0[id] - y0[io]), d = std::hypot(p.x[q] - p.x[o], p.y[q] - p.y[o]);
            r.dist_err = std::max(r.dist_err, std::fabs(d - d0) / d0);
        }
    }
    r.angle = 0.5 * std::atan2(2 * sxy, sxx - syy) * 180 / kPi;
    const double omega = w / s.dt_s;
    r.centripetal = 2000 * omega * omega * 1.25;  // rho omega^2 R^2, R^2 = 1 + 0.5^2 m^2
    r.energy_gain = (e.max - e.first) / e.first;
    r.energy_end = e.last / e.first;
    return r;
}

void report(const char* what, const Spin& r, double L) {
    MESSAGE(std::string(what) << " spin on L = " << L << " m: major axis at " << r.angle << " deg (90 expected, the sign is atan2's), point position error up to "
                 << r.pos_err << " m, distances changed up to " << r.dist_err * 100 << " %, stress up to " << r.stress << " Pa = "
                 << r.stress / r.centripetal << " rho omega^2 R^2; shadow energy up to +" << r.energy_gain * 100 << " %, at the end "
                 << r.energy_end << " of the start");
}

}  // namespace

// The shadow energy of the spinning block rises above its start before it falls (no
// source: a defect). Like the 2 m drop's, it is a resolution error that falls with L
// (measured +2.8 %, +1.2 %, +0.37 % at L = 0.25, 0.125, 0.0625 m). It is above eq. 12's
// own share: on a rigid rotation by w per step eq. 12 scales |du|^2 by 1 + w^2 each step,
// (pi/2)^2 / n = 1.2e-3, 6.2e-4, 3.1e-4 over the n steps of the quarter turn.
TEST_CASE("hard: a stress-free block spun as a rigid body through 90 degrees keeps its shape and stays nearly stress-free; its energy excess falls with L [slow]") {
    const Spin a = spin(1), b = spin(2), c = spin(4);
    report("eq. 12", a, 0.25);
    report("eq. 12", b, 0.125);
    report("eq. 12", c, 0.0625);
    for (const Spin* r : {&a, &b, &c}) {
        CHECK(r->ok);
        CHECK(r->mass);
        CHECK(r->energy_end < 1.0);
    }
    // Measured 86.3 deg, 0.092 m, 28 %, 25 kPa at L = 0.25 m; 88.6 deg, 0.033 m, 14 %,
    // 14 kPa at L = 0.125 m: a first-order lag and distortion, not a breakdown. The bounds
    // hold the measured values, and the finer lattice must do better.
    CHECK(a.angle > 85);
    CHECK(b.angle > 88);
    CHECK(c.angle > b.angle);
    CHECK(a.pos_err < 0.5 * 0.25);
    CHECK(b.pos_err < 0.6 * a.pos_err);
    CHECK(c.pos_err < 0.6 * b.pos_err);
    CHECK(b.dist_err < 0.6 * a.dist_err);
    CHECK(b.stress < a.stress);
    CHECK(c.stress < b.stress);
    // The energy excess: at least first order in L.
    CHECK(b.energy_gain < 0.6 * a.energy_gain);
    CHECK(c.energy_gain < 0.6 * b.energy_gain);
}

// ADVECT POINTS carries each cell's affine increment field on its points, so a rigid
// rotation survives the remapping: the block turns with it instead of lagging and
// shearing. What stress remains is the physical one, rho omega^2 R^2: a free elastic block
// must be held together to spin rigidly. The nodal shadow energy is a poor measure here:
// the lumped masses sit at nodes, so the block's nodal moment of inertia changes as it
// turns over the lattice while omega does not (+8.6 %, +2.4 % at L = 0.25, 0.125 m,
// falling as L^2); at the end the energy is 0.997 and 0.9985 of the start.
TEST_CASE("hard: ADVECT POINTS turns a rigid body through 90 degrees with its shape kept to 1 % of a cell [slow]") {
    const Spin a = spin(1, Advect::Points, Motion::Centre), b = spin(2, Advect::Points, Motion::Centre);
    const Spin bl = spin(1, Advect::Points, Motion::Bilinear);
    report("ADVECT POINTS, MOTION CENTRE", a, 0.25);
    report("ADVECT POINTS, MOTION CENTRE", b, 0.125);
    report("ADVECT POINTS, MOTION BILINEAR", bl, 0.25);
    for (const Spin* r : {&a, &b, &bl}) {
        CHECK(r->ok);
        CHECK(r->mass);
        // A turn short by d moves the outermost points, a quarter cell inside the corners
        // (1.035 m from the centre at L = 0.25, 1.076 m at 0.125), by that radius times d: the
        // positions' bound below (2 % of a cell, 5 mm) allows 0.27-0.28 deg. The corners'
        // radius hypot(1, 0.5) gives the bound for both, 0.26 deg.
        CHECK(std::fabs(std::fabs(r->angle) - 90) < 0.02 * 0.25 / std::hypot(1.0, 0.5) / kDeg);
        CHECK(r->pos_err < 0.02 * 0.25);                  // eq. 12: 0.093 m
        CHECK(r->dist_err < 0.01);                        // eq. 12: 28 %
        CHECK(r->stress < 1.5 * r->centripetal);          // eq. 12: 16 rho omega^2 R^2
        CHECK(r->energy_end < 1.0);
        CHECK(r->energy_end > 0.99);
    }
    CHECK(b.pos_err < 0.6 * a.pos_err);
    CHECK(b.energy_gain < 0.6 * a.energy_gain);
}

// ----------------------------------------------------------- checkerboard ---

namespace {

struct Checker {
    double ke_max = 0, ke_end = 0, shadow_max = 0, stress_early = 0, stress = 0, drift = 0, drift_early = 0;
    bool ok = true, mass = true;
};

// A free elastic 8 x 8-cell block at rest, no gravity, no damping, dt = 0.5 of the limit;
// the nodal increments set to the checkerboard (-1)^(i+j) a (1, 1), a = 10^-4 L.
Checker checkerboard(long n, double kappa, Motion motion = Motion::Paper) {
    Scene s = elastic_scene(12, 12, 0.5, {1, 1, 5, 5});
    s.dt_s = 0.5 * stable_dt(s);
    s.motion = motion;
    s.hourglass = kappa;  // HOURGLASS: viscous control of the mode; 0 = the paper's cycle
    Simulation sim(s);
    const Points& p = sim.points();
    const std::vector<double> x0(p.x.begin(), p.x.end()), y0(p.y.begin(), p.y.end());
    const double a = 1e-4 * s.cell_m;
    set_increments(sim, [&](int i, int j, double, double, double& ux, double& uy) { ux = uy = (i + j) % 2 ? -a : a; });
    Shadow e;
    Checker c;
    double ke0 = 0;
    for (long k = 0; k < n; ++k) {
        e.checked(sim);
        if (k == 0) ke0 = sim.kinetic_energy();
        c.ke_max = std::max(c.ke_max, sim.kinetic_energy() / ke0);
        for (std::size_t q = 0; q < p.size(); ++q) {
            const double sq = std::max({std::fabs(p.sxx[q]), std::fabs(p.syy[q]), std::fabs(p.sxy[q])});
            c.stress = std::max(c.stress, sq);
            if (k < 1000) c.stress_early = std::max(c.stress_early, sq);
        }
        if (k == 999)
            for (std::size_t q = 0; q < p.size(); ++q)
                c.drift_early = std::max(c.drift_early, std::hypot(p.x[q] - x0[std::size_t(p.id[q])], p.y[q] - y0[std::size_t(p.id[q])]) / s.cell_m);
    }
    c.ok = e.ok;
    c.mass = e.mass;
    for (std::size_t q = 0; q < p.size(); ++q)
        c.drift = std::max(c.drift, std::hypot(p.x[q] - x0[std::size_t(p.id[q])], p.y[q] - y0[std::size_t(p.id[q])]) / s.cell_m);
    c.ke_end = sim.kinetic_energy() / ke0;
    c.shadow_max = e.max / e.first;
    return c;
}

}  // namespace

TEST_CASE("hard: checkerboard nodal increments in a block at rest: what the paper's cycle does with them [slow]") {
    // Eq. 5 does not see the mode: no strain, no stress, no force, so the increments stay
    // and (eq. 7a/7b about node [1]) the points of neighbouring cells drift apart at a per
    // step. Once they have crossed cell edges the mixed points carry stress, and the
    // mode's energy grows.
    const Checker c = checkerboard(40000, 0);
    MESSAGE("checkerboard, 40 000 steps: stress in the first 1000 steps " << c.stress_early << " Pa, points drifted " << c.drift_early
                                                                        << " L by then; later stress up to " << c.stress << " Pa, drift "
                                                                        << c.drift << " L; kinetic energy up to " << c.ke_max << ", at the end "
                                                                        << c.ke_end << " of the start; shadow energy up to " << c.shadow_max);
    CHECK(c.ok);
    CHECK(c.mass);
    CHECK(c.stress_early == 0);                 // invisible to eq. 5 ...
    CHECK(c.drift_early > 0.1);                 // ... so nothing stops the points drifting
    CHECK(c.ke_end > 0.1);                      // the mode lives
    // In the paper's cycle its energy even grows (shadow energy up to 3 times the start in
    // 40 000 steps): points of neighbouring cells cross into each other and carry stress.
    // HOURGLASS keeps the mode from starting (next test).
}

TEST_CASE("hard: with MOTION CENTRE (the default) the checkerboard moves no point [slow]") {
    // The mean of the mode's four increments in every cell is zero, and so is its part in
    // the affine map about the centre: the points stay, nothing crosses an edge, no stress.
    const Checker c = checkerboard(40000, 0, Motion::Centre);
    MESSAGE("checkerboard with MOTION CENTRE: drift " << c.drift << " L, stress up to " << c.stress << " Pa, kinetic energy at the end " << c.ke_end);
    CHECK(c.ok);
    CHECK(c.mass);
    CHECK(c.drift == 0.0);
    CHECK(c.stress == 0.0);
    CHECK(c.shadow_max <= 1 + 1e-9);
}

TEST_CASE("hard: HOURGLASS 0.01 removes the checkerboard and its energy never grows [slow]") {
    // The smallest remedy, the kernel's HOURGLASS option: a viscous force on the pattern
    // (+1, -1, -1, +1) alone; affine fields are untouched (tests/test_cycle.cpp).
    const Checker c = checkerboard(40000, 0.01);
    MESSAGE("with kappa = 0.01: kinetic energy at the end " << c.ke_end << " of the start, shadow energy never above " << c.shadow_max
                                                           << ", stress up to " << c.stress << " Pa, drift " << c.drift << " L");
    CHECK(c.ok);
    CHECK(c.mass);
    CHECK(c.ke_end < 1e-3);
    CHECK(c.shadow_max <= 1 + 1e-9);
    CHECK(c.drift < 0.1);
}

// ------------------------------------------------------------------ points ---

TEST_CASE("hard: one point per cell: the confined column still comes to rest at the reference stress") {
    Scene s;
    REQUIRE(read_deck("decks/column.deck", s).empty());
    s.clusters[0].ppc = 1;
    Simulation sim(s);
    const Points& p = sim.points();
    const std::vector<double> y0(p.y.begin(), p.y.end());
    Shadow e;
    e.run(sim, s.steps);
    double num = 0, den = 0;
    for (std::size_t k = 0; k < p.size(); ++k) {
        const double ref = -2000 * 9.81 * (12 - y0[std::size_t(p.id[k])]);
        num += std::pow(p.syy[k] - ref, 2);
        den += ref * ref;
    }
    MESSAGE("one point per cell: sigma_yy L2 error " << std::sqrt(num / den) << " (2 x 2 points: 1.96 %), unbalanced ratio " << sim.unbalanced_ratio());
    CHECK(e.ok);
    CHECK(e.mass);
    CHECK(std::sqrt(num / den) < 0.03);
    CHECK(sim.unbalanced_ratio() < 1e-6);
    CHECK(e.max <= e.first + 1e-9 * std::fabs(e.first));
}

TEST_CASE("hard: isolated points fall onto a fixed floor and stay on it") {
    // Five lone points (one cell each, one point per cell), far apart, at different
    // heights, damped; each is a cell of material of its own all the way down.
    Scene s = elastic_scene(20, 12, 0.5, {0.5, 5, 1, 5.5}, 1);
    s.clusters.clear();
    for (int q = 0; q < 5; ++q) {
        const double x = 0.5 + 2.0 * q, y = 1.0 + 1.0 * q;
        s.clusters.push_back({1, {x + 0.1, y + 0.1, x + 0.4, y + 0.4}, 1, {}});  // one cell centre
    }
    s.fixes.push_back({kFixX | kFixY, {0, 0, 10, 0}, {}});
    s.gravity_y = -9.81; s.damping = 0.5;
    s.dt_s = 0.5 * stable_dt(s);  // below the lone-cell and damping limits (findings above)
    for (const auto& d : validate(s)) MESSAGE(d.str());
    REQUIRE(validate(s).empty());
    Simulation sim(s);
    const Points& p = sim.points();
    REQUIRE(p.size() == 5);
    Shadow e;
    double ymin = 1e300;
    const long n = long(2.0 / s.dt_s);
    for (long k = 0; k < n && e.ok; ++k) {
        e.checked(sim);
        for (double y : p.y) ymin = std::min(ymin, y);
    }
    double ytop = 0;
    for (double y : p.y) ytop = std::max(ytop, y);
    MESSAGE("isolated points after 2 s: heights " << ymin << " .. " << ytop << " m (lowest ever " << ymin << "), kinetic energy "
                                                  << sim.kinetic_energy() << " J/m, shadow energy max - start " << e.max - e.first);
    CHECK(e.ok);
    CHECK(e.mass);
    CHECK(sim.mass_outflow() == 0);  // none passes the floor
    CHECK(p.size() == 5);
    CHECK(ymin > 0);
    CHECK(ytop < 0.5);  // all came down into the cells on the floor
    CHECK(e.max <= e.first + 1e-9 * std::fabs(e.first));
}

TEST_CASE("hard: points exactly on cell edges, nodes and the lattice boundary move exactly with a translation") {
    // A stress-free block of one point per cell, every point moved onto a node or the
    // middle of an edge (x = 0 and y = 0 included: the lower and left lattice edges),
    // then translated by the same increment at every node: no strain, exact motion.
    Scene s = elastic_scene(8, 8, 0.5, {0, 0, 2, 2}, 1);
    s.dt_s = 1e-4;
    Simulation sim(s);
    Points& p = sim.points();
    for (std::size_t k = 0; k < p.size(); ++k) {
        const int c = p.cell[k], i = c % sim.mx(), j = c / sim.mx();
        p.x[k] = i * 0.5;                        // on the left edge of its cell
        p.y[k] = (k % 2) ? j * 0.5 : j * 0.5 + 0.25;  // on a node or an edge's middle
    }
    const std::vector<double> x0(p.x.begin(), p.x.end()), y0(p.y.begin(), p.y.end());
    const double ux = 1e-4, uy = 7e-5;
    set_increments(sim, [&](int, int, double, double, double& a, double& b) { a = ux; b = uy; });
    Health h;
    double stress = 0;
    const long n = 2000;
    for (long k = 0; k < n; ++k) {
        sim.step();
        h.check(sim);
        for (std::size_t q = 0; q < p.size(); ++q) stress = std::max({stress, std::fabs(p.sxx[q]), std::fabs(p.syy[q]), std::fabs(p.sxy[q])});
    }
    double err = 0;
    for (std::size_t q = 0; q < p.size(); ++q) {
        const std::size_t id = std::size_t(p.id[q]);
        err = std::max({err, std::fabs(p.x[q] - (x0[id] + n * ux)), std::fabs(p.y[q] - (y0[id] + n * uy))});
    }
    MESSAGE("points on edges after " << n << " steps of translation: position error up to " << err << " m, stress up to " << stress << " Pa");
    CHECK(h.ok);
    CHECK(h.mass);
    CHECK(p.size() == 16);
    CHECK(err < 1e-12);
    CHECK(stress < 1e-6);
}

TEST_CASE("hard: a point exactly on the upper or right lattice edge has left; on the lower or left edge it is inside") {
    Scene s = elastic_scene(4, 4, 0.5, {0, 0, 2, 2}, 1);
    s.dt_s = 1e-4;
    Simulation sim(s);
    Points& p = sim.points();
    REQUIRE(p.size() == 16);
    // Points 0 and 1 onto x = 0 and y = 0, points 15 and 14 onto x = X and y = Y, at rest.
    p.x[0] = 0.0;
    p.y[1] = 0.0;
    p.x[15] = 2.0;   // their cell (3, 3) stays as it was: eq. 7 moves them, then they are out
    p.y[14] = 2.0;
    sim.step();
    CHECK(p.size() == 14);
    CHECK(sim.mass_outflow() == 2 * sim.point_mass(0));
    CHECK(mass_exact(sim));
    CHECK(finite(sim));
    bool zero_kept = false, one_kept = false;
    for (std::size_t k = 0; k < p.size(); ++k) { zero_kept |= p.id[k] == 0; one_kept |= p.id[k] == 1; }
    CHECK(zero_kept);
    CHECK(one_kept);
}

TEST_CASE("hard: points leave through every side; mass balance exact at every step; the empty lattice keeps stepping") {
    struct Side { const char* name; double gx, gy; };
    for (const Side side : {Side{"left", -9.81, 0}, Side{"right", 9.81, 0}, Side{"bottom", 0, -9.81}, Side{"top", 0, 9.81}}) {
        Scene s = elastic_scene(10, 10, 0.25, {1, 1, 1.5, 1.5}, 3);
        s.gravity_x = side.gx; s.gravity_y = side.gy;
        s.dt_s = 1e-3;
        Simulation sim(s);
        Health h;
        bool monotone = true;
        double out = 0;
        long emptied = -1;
        for (long k = 0; k < 1500; ++k) {
            sim.step();
            h.check(sim);
            monotone &= sim.mass_outflow() >= out;
            out = sim.mass_outflow();
            if (emptied < 0 && (sim.points().size() == 0)) emptied = k;
        }
        MESSAGE("through the " << std::string(side.name) << " side: the lattice emptied at step " << emptied);
        CHECK(h.ok);
        CHECK(h.mass);
        CHECK(monotone);
        CHECK(emptied > 0);
        CHECK((sim.points().size() == 0));
        CHECK(sim.mass_inside() == 0);
        CHECK(sim.mass_outflow() == sim.mass_initial());
        CHECK(sim.kinetic_energy() == 0);
    }
}

TEST_CASE("hard: no point crosses a fixed edge: a granular column collapses on a rough floor against a smooth wall") {
    // The coarsest rung of the collapse (decks/verify_collapse.deck, a = 0.5: 1 m x 0.5 m,
    // L = 0.125 m, no damping, 4 s). Eq. 7a/7b alone let 14 % (2 x 2 points per cell) and
    // 22 % (1 x 1) of the mass out through the floor; every point must stay at y >= 0 (the
    // rough floor, fixed in x and y) and x >= 0 (the smooth wall, fixed in x).
    for (const Motion motion : {Motion::Paper, Motion::Centre})
        for (const int ppc : {1, 2}) {
            Scene s;
            s.mx = 80; s.my = 34; s.cell_m = 0.125;
            s.materials.push_back(Material::mohr(1, 1e7, 0.3, 2000, 30, 0));
            s.clusters.push_back({1, {0, 0, 1, 0.5}, ppc, {}});
            s.fixes.push_back({kFixX, {0, 0, 0, 4.25}, {}});
            s.fixes.push_back({kFixX | kFixY, {0, 0, 10, 0}, {}});
            s.gravity_y = -9.81; s.dt_s = 5e-4; s.steps = 8000; s.motion = motion;
            REQUIRE(validate(s).empty());
            Simulation sim(s);
            const Points& p = sim.points();
            Health h;
            double xmin = 1e300, ymin = 1e300, xmax = 0;
            for (long k = 0; k < s.steps && h.ok; ++k) {
                sim.step();
                h.check(sim);
                for (std::size_t q = 0; q < p.size(); ++q) { xmin = std::min(xmin, p.x[q]); ymin = std::min(ymin, p.y[q]); xmax = std::max(xmax, p.x[q]); }
            }
            MESSAGE("collapse a = 0.5, " << ppc << " x " << ppc << " points, motion " << int(motion) << ": outflow " << sim.mass_outflow()
                                         << " kg/m, lowest point y = " << ymin << ", x = " << xmin << ", front at x = " << xmax);
            CHECK(h.ok);
            CHECK(h.mass);
            CHECK(sim.mass_outflow() == 0);
            CHECK(ymin >= 0);
            CHECK(xmin >= 0);
            CHECK(xmax > 1.1);  // it did collapse and spread
        }
}

// ------------------------------------------------------------------- wall ---

namespace {

struct Push {
    double work = 0, fmax = 0, fmean = 0, excess = -1e300, travel = 0, ke_end = 0, vol_ratio = 0;
    long bad = -1;
    bool mass = true;
};

// Mohr-Coulomb soil 3 m x 1 m (L = 0.1 m) on a rough base between smooth sides, under
// gravity, damping 0.5, dt = 0.5 of the limit; a vertical wall of 7 nodes at x = 0.5 m
// driven at 0.1 L per step (0.2 c_p) for 150 steps (1.5 m, 15 lines of nodes), then,
// if rest > 0, held still for rest steps. excess: the largest shadow energy above its
// start plus the work of the wall.
Push push_wall(long rest) {
    Scene s;
    s.mx = 30; s.my = 14; s.cell_m = 0.1;
    s.materials.push_back(Material::mohr(1, 2e7, 0.3, 1800, 30, 2e3));
    s.clusters.push_back({1, {0, 0, 3, 1}, 2, {}});
    s.fixes.push_back({kFixX, {0, 0, 0, 1.4}, {}});
    s.fixes.push_back({kFixX, {3, 0, 3, 1.4}, {}});
    s.fixes.push_back({kFixX | kFixY, {0, 0, 3, 0}, {}});
    s.gravity_y = -9.81; s.damping = 0.5; s.steps = 150;
    s.dt_s = 0.5 * stable_dt(s);
    s.walls.push_back({1, {0.5, 0.2, 0.5, 0.8}, 0.1 * (1 - 1e-12) * s.cell_m / s.dt_s, 0, {}});  // the largest speed allowed
    REQUIRE(validate(s).empty());
    Simulation sim(s);
    Shadow e;
    Push r;
    double base = 0;
    for (long k = 0; k < s.steps + rest && r.bad < 0; ++k) {
        if (k == s.steps) sim.set_wall_velocity(1, 0, 0);
        e.step(sim);
        if (!finite(sim)) r.bad = k;
        r.mass &= mass_exact(sim);
        const WallState& w = sim.walls()[0];
        if (k < s.steps) {
            r.work += w.fx * s.walls[0].vx * s.dt_s;  // the force it exerts times its increment
            r.fmax = std::max(r.fmax, std::fabs(w.fx));
            r.fmean += w.fx / double(s.steps);
        }
        // The wall's own nodes are part of the driver: their kinetic energy is handed to them
        // by the prescription, not by the force; leave it out of the soil's energy.
        // (Both lines of nodes while the wall's face lies between them: driven_nodes.)
        double wall_ke = 0;
        for (const std::int32_t m : sim.driven_nodes()) {
            const std::size_t n = std::size_t(m);
            wall_ke += 0.5 * sim.node_mass()[n] * (e.px[n] * sim.du_x()[n] + e.py[n] * sim.du_y()[n]) / (s.dt_s * s.dt_s);
        }
        if (k == 0) base = e.last - wall_ke;
        r.excess = std::max(r.excess, e.last - wall_ke - base - r.work);
    }
    r.travel = sim.walls()[0].dx;
    r.ke_end = sim.kinetic_energy();
    for (std::size_t q = 0; q < sim.points().size(); ++q) r.vol_ratio = std::max(r.vol_ratio, sim.points().vol[q] * 1800 / sim.point_mass(q));
    return r;
}

}  // namespace

TEST_CASE("hard: a wall pushed through a soil mass at a tenth of a cell per step") {
    const Push r = push_wall(0);
    MESSAGE("wall through soil: travel " << r.travel << " m, mean force " << r.fmean << " N/m, largest " << r.fmax << " N/m, work " << r.work
                                        << " J/m; shadow energy above start + work at most " << r.excess << " J/m; unhealthy at step " << r.bad
                                        << "; largest point volume " << r.vol_ratio << " x its initial");
    CHECK(r.bad == -1);
    CHECK(r.mass);
    CHECK(r.travel == approx(1.5).epsilon(1e-9));
    CHECK(r.fmean > 0);                 // on average the wall pushes the soil the way it moves
    CHECK(r.excess <= 1e-6 * r.work);   // no energy beyond the wall's work
}

// Found here: after the push, with the wall at rest, the run went unstable (step 463 of
// the rest). Points that fail in tension dilate without bound (up to 53-79 times their
// volume); eq. 8 made a cell's stiffness grow with sum V while its mass stayed. The kernel
// now smears at most a point's initial volume m / rho_0.
TEST_CASE("hard: soil pushed by a wall then left at rest settles without blowing up") {
    const Push r = push_wall(3000);
    MESSAGE("push then 3000 steps at rest: unhealthy at step " << r.bad << ", kinetic energy " << r.ke_end << " J/m, largest point volume "
                                                              << r.vol_ratio << " x its initial");
    CHECK(r.bad == -1);
    CHECK(r.excess <= 1e-6 * r.work);
    CHECK(r.ke_end < 1e-3 * r.work);
}

// ------------------------------------------------------------------ SHIFT ---

namespace {

struct Flow {
    double most = 0;   // the largest packing() over every step
    double out = 0;    // the mass that left through the slot [kg/m]
    long shifted = 0;
    long crossed = 0;  // steps in which a point crossed the floor (y = 1) beside the slot
    bool mass = true;
};

// decks/verify_hopper.deck (a bin of cohesionless sand emptying through a slot, 2 s),
// with or without SHIFT (its defaults), the paper's cycle or ADVECT FLIP.
Flow hopper(bool shift, bool flip) {
    Scene s;
    REQUIRE(read_deck("decks/verify_hopper.deck", s).empty());
    s.outputs.clear();
    s.shift = shift;
    if (flip) { s.mapping = Mapping::Smooth; s.advect = Advect::Flip; }
    REQUIRE(validate(s).empty());
    Simulation sim(s);
    Flow r;
    const Points& p = sim.points();
    std::vector<double> x0(p.size()), y0(p.size());  // by id: where each point was a step before
    for (std::size_t k = 0; k < p.size(); ++k) { x0[std::size_t(p.id[k])] = p.x[k]; y0[std::size_t(p.id[k])] = p.y[k]; }
    for (long k = 0; k < s.steps; ++k) {
        sim.step();
        r.most = std::max(r.most, sim.packing());
        r.mass &= mass_exact(sim);
        bool crossed = false;
        for (std::size_t q = 0; q < p.size(); ++q) {
            const std::size_t i = std::size_t(p.id[q]);
            if (y0[i] >= 1 && p.y[q] < 1 && (std::min(x0[i], p.x[q]) < 2.5 || std::max(x0[i], p.x[q]) > 3.5)) crossed = true;
            x0[i] = p.x[q]; y0[i] = p.y[q];
        }
        r.crossed += crossed;
    }
    r.out = sim.mass_outflow();
    r.shifted = sim.shifted();
    return r;
}

}  // namespace

// The invariant (#packing, tests/README.md): no cell's points hold more than twice its
// area unless they were compressed that much. The hopper's cells hold up to 3.75 times
// (the paper's cycle) and 2.5 times (ADVECT FLIP) without SHIFT, the points' volumes all but
// unchanged. With it every step's cells stay within twice their area under either cycle
// (under the paper's, the passes alone left nine points of V0 in a cell made with 2 x 2,
// 2.25, at the slot's corners: eq. 12's cell-wise motion brings them between passes, and
// the guard after every step, shift_relief, moves one out). The discharge is the
// flow's own measure: the slot's rate must not move by more than the 2 % by which
// the rate's own scatter between runs differs.
TEST_CASE("hard: SHIFT holds a draining hopper's cells within twice their area, and the discharge as it was [slow]") {
    for (const bool flip : {false, true}) {
        const Flow off = hopper(false, flip), on = hopper(true, flip);
        MESSAGE(std::string(flip ? "ADVECT FLIP" : "the paper's cycle") << ": packing " << off.most << " -> " << on.most << " with SHIFT (" << on.shifted
                << " moves), discharge " << off.out << " -> " << on.out << " kg/m");
        CHECK(off.shifted == 0);
        CHECK(on.shifted > 0);
        CHECK(off.crossed == 0);
        CHECK(on.crossed == 0);  // the passes do not carry points across the floor's fixed edges
        CHECK(off.most > 2.4);  // packed without it: the case is a test
        CHECK(on.most <= 2.0);
        CHECK(on.mass);
        CHECK(on.out == approx(off.out).epsilon(0.02));
    }
}

namespace {

// The guard's scenes: a weightless elastic block (nothing moves but what SHIFT moves), 2 x 2
// points in cells of 0.1 m on a lattice of mx x 20 cells, one step with SHIFT (its
// defaults), in the given cycle (the paper's mapping unless one is named).
Scene guard_block(Box box, int mx = 20, const Cycle& cycle = kCycles[0]) {
    Scene s;
    s.mx = mx; s.my = 20; s.cell_m = 0.1;
    s.gravity_y = 0;
    s.materials.push_back(Material::elastic(1, 1e7, 0.3, 2000));
    s.clusters.push_back({1, box, 2, {}});
    cycle.apply(s);
    s.shift = true;
    s.steps = 1;
    s.dt_s = 0.5 * stable_dt(s);
    return s;
}

// One point of the cell holding (fx, fy) moved to (tx, ty); false if that cell holds none.
bool give(Simulation& sim, double fx, double fy, double tx, double ty) {
    Points& p = sim.points();
    const int c = sim.cell_holding(fx, fy);
    for (std::size_t k = 0; k < p.size(); ++k)
        if (p.cell[k] == c) { p.x[k] = tx; p.y[k] = ty; p.cell[k] = sim.cell_holding(tx, ty); return true; }
    return false;
}

// The points of the cell whose lower left corner is (x0, y0) still where they were made (at
// a quarter and three quarters of the cell across) moved to `to`; how many there were.
int put_own(Simulation& sim, double x0, double y0, const double (&to)[4][2]) {
    Points& p = sim.points();
    const int c = sim.cell_holding(x0 + 0.05, y0 + 0.05);
    int m = 0;
    for (std::size_t k = 0; k < p.size(); ++k)
        if (p.cell[k] == c && (std::fabs(p.x[k] - (x0 + 0.025)) < 1e-9 || std::fabs(p.x[k] - (x0 + 0.075)) < 1e-9)) {
            if (m < 4) { p.x[k] = to[m][0]; p.y[k] = to[m][1]; p.cell[k] = sim.cell_holding(to[m][0], to[m][1]); }
            ++m;
        }
    return m;
}

}  // namespace

// SHIFT's guard (shift_relief), with a known answer: a weightless block at rest (nothing
// moves but what SHIFT moves), cells of 0.1 m made with 2 x 2 points, cell (10, 10) given
// six points of its neighbours (one from each of six: ten points of L^2 / 4, 2.5 times its
// area). After one step (no pass: those come every 10) the cell holds eight, twice its
// area, and no cell more; exactly two points moved, each along one axis to L / 1000
// beyond an edge of that cell, into the cell there, and they were the points nearest an
// edge (the guard takes the smallest moves); no energy made. Variants: the cell's four
// corner nodes fixed (its edges fixed): nothing may leave, no move; its left and lower
// neighbours filled to eight points (no room there) and the cell's own four points put
// nearest those edges: the two that move are the nearest the right and upper edges, and
// go right or up. Each mapping, and ADVECT FLIP.
TEST_CASE("hard: SHIFT's guard empties a cell holding more than twice its area by the smallest moves") {
    enum Variant { kOpen, kFixed, kFull };
    for (const Cycle& cycle : kCycles)
        for (const Variant variant : {kOpen, kFixed, kFull}) {
            Scene s = guard_block({0.5, 0.5, 1.5, 1.5}, 20, cycle);
            if (variant == kFixed)
                for (const double x : {1.0, 1.1})
                    for (const double y : {1.0, 1.1}) s.fixes.push_back({kFixX | kFixY, {x, y, x, y}, {}});
            REQUIRE(validate(s).empty());
            Simulation sim(s);
            Points& p = sim.points();
            const double L = s.cell_m;
            const int target = sim.cell_holding(1.05, 1.05);
            REQUIRE(give(sim, 0.95, 1.05, 1.04, 1.05));
            REQUIRE(give(sim, 1.15, 1.05, 1.06, 1.05));
            REQUIRE(give(sim, 1.05, 0.95, 1.05, 1.04));
            REQUIRE(give(sim, 1.05, 1.15, 1.05, 1.062));
            REQUIRE(give(sim, 0.95, 0.95, 1.045, 1.058));
            REQUIRE(give(sim, 1.15, 1.15, 1.058, 1.043));
            if (variant == kFull) {  // cells (9, 10) and (10, 9), three points each now, given five more each
                for (int n = 0; n < 5; ++n) {  // from cells 8 .. 5 along the row (down the column) and the one beside 8
                    const double far = n < 4 ? 0.85 - 0.1 * n : 0.85, side = n < 4 ? 1.05 : 1.15, at = 0.94 + 0.005 * n, across = 1.03 + 0.01 * n;
                    REQUIRE(give(sim, far, side, at, across));
                    REQUIRE(give(sim, side, far, across, at));
                }
                // and the cell's own four points put nearest its left and lower edges
                REQUIRE(put_own(sim, 1.0, 1.0, {{1.01, 1.05}, {1.05, 1.01}, {1.015, 1.03}, {1.03, 1.015}}) == 4);
            }
            sim.map_to_lattice();
            const std::vector<double> x0(p.x), y0(p.y);
            auto edge_distance = [&](std::size_t k) {  // to the nearest edge with room beyond it
                const double u = x0[k] / L - 10, v = y0[k] / L - 10;
                return L * (variant == kFull ? std::min(1 - u, 1 - v) : std::min({u, 1 - u, v, 1 - v}));
            };
            sim.step();
            std::map<int, int> count;
            for (std::size_t k = 0; k < p.size(); ++k) ++count[p.cell[k]];
            int most = 0;
            for (const auto& [c, n] : count) most = std::max(most, n);
            const std::string name = std::string(cycle.name) + (variant == kFixed ? ", the cell's edges fixed" : variant == kFull ? ", its left and lower neighbours full" : "");
            MESSAGE(name << ": " << sim.shifted() << " moves, the cell holds " << count[target] << " points, no cell more than " << most);
            CHECK(mass_exact(sim));
            CHECK(std::fabs(sim.energy().error) < 1e-12);
            for (std::size_t k = 0; k < p.size(); ++k) CHECK(p.cell[k] == sim.cell_holding(p.x[k], p.y[k]));
            if (variant == kFixed) {
                CHECK(sim.shifted() == 0);
                CHECK(count[target] == 10);
                continue;
            }
            CHECK(sim.shifted() == 2);
            CHECK(count[target] == 8);
            CHECK(most == 8);
            double nearest_stayed = L, farthest_moved = 0;
            int moved = 0;
            for (std::size_t k = 0; k < p.size(); ++k) {
                const bool was = x0[k] >= 1.0 && x0[k] < 1.1 && y0[k] >= 1.0 && y0[k] < 1.1;
                if (p.x[k] == x0[k] && p.y[k] == y0[k]) {
                    if (was) nearest_stayed = std::min(nearest_stayed, edge_distance(k));
                    continue;
                }
                ++moved;
                CHECK(was);
                CHECK((p.x[k] == x0[k] || p.y[k] == y0[k]));  // along one axis
                const double off = std::min({std::fabs(p.x[k] - 1.0), std::fabs(p.x[k] - 1.1), std::fabs(p.y[k] - 1.0), std::fabs(p.y[k] - 1.1)});
                CHECK(off == approx(1e-3 * L).epsilon(1e-6));
                CHECK(p.cell[k] != target);
                if (variant == kFull) CHECK((p.x[k] > 1.1 || p.y[k] > 1.1));  // right or up: the full ones took none
                farthest_moved = std::max(farthest_moved, edge_distance(k));
            }
            CHECK(moved == 2);
            CHECK(farthest_moved <= nearest_stayed);
        }
}

// The guard at the lattice's corner: the same block put in the lattice's lower left corner,
// cell (0, 0) given six of its neighbours' points. Its own points lie nearest the
// lattice's edges, beyond which there is no cell: the two that move go right or up, to the
// points nearest those edges, and every point stays on the lattice.
TEST_CASE("hard: SHIFT's guard moves no point off the lattice") {
    const Scene s = guard_block({0, 0, 1, 1});
    REQUIRE(validate(s).empty());
    Simulation sim(s);
    Points& p = sim.points();
    const double from[6][2] = {{0.15, 0.05}, {0.05, 0.15}, {0.15, 0.15}, {0.25, 0.05}, {0.05, 0.25}, {0.25, 0.25}};
    const double spots[6][2] = {{0.04, 0.05}, {0.06, 0.05}, {0.05, 0.04}, {0.05, 0.062}, {0.045, 0.058}, {0.058, 0.043}};
    for (int n = 0; n < 6; ++n) REQUIRE(give(sim, from[n][0], from[n][1], spots[n][0], spots[n][1]));
    REQUIRE(put_own(sim, 0, 0, {{0.01, 0.05}, {0.05, 0.01}, {0.015, 0.03}, {0.03, 0.015}}) == 4);  // the cell's own, nearest the lattice's edges
    sim.map_to_lattice();
    const std::vector<double> x0(p.x), y0(p.y);
    sim.step();
    int in_corner = 0, moved = 0;
    for (std::size_t k = 0; k < p.size(); ++k) {
        CHECK(p.cell[k] >= 0);
        CHECK(p.cell[k] == sim.cell_holding(p.x[k], p.y[k]));
        in_corner += p.cell[k] == 0;
        if (p.x[k] == x0[k] && p.y[k] == y0[k]) continue;
        ++moved;
        CHECK((p.x[k] > 0.1 || p.y[k] > 0.1));  // right or up
        CHECK((std::fabs(x0[k] - 0.06) < 1e-12 || std::fabs(y0[k] - 0.062) < 1e-12));  // the two nearest those edges
    }
    MESSAGE("the corner cell: " << sim.shifted() << " moves, " << in_corner << " points left in it");
    CHECK(moved == 2);
    CHECK(in_corner == 8);
    CHECK(sim.mass_outflow() == 0);
    CHECK(mass_exact(sim));
}

// The guard beside a wall: the weightless block with a SMOOTH wall at rest along x = 1 m
// through it. The cells within two of the wall's face (x 0.8 to 1.2 m) are the wall's
// (kEdgeWall: its own guard of the face acts there): the guard moves no point out of them
// or into them. Cell (10, 10), on the face, given six of its neighbours' points keeps its
// ten; cell (13, 10), beside the wall's cells, given six of its neighbours' points (not of
// the wall's cells) with its own points nearest its left edge, gives two, none to the
// left.
TEST_CASE("hard: SHIFT's guard moves no point out of or into the cells of a wall's face") {
    Scene s = guard_block({0.5, 0.5, 2.0, 1.5}, 30);
    Wall w;
    w.id = 1; w.box = {1.0, 0.3, 1.0, 1.7}; w.smooth = true;
    s.walls.push_back(w);
    REQUIRE(validate(s).empty());
    Simulation sim(s);
    Points& p = sim.points();
    for (const double cx : {1.05, 1.35}) {  // cells (10, 10) and (13, 10)
        const double from[6][2] = {{cx + 0.1, 1.15}, {cx + 0.1, 0.95}, {cx, 1.25}, {cx, 0.85}, {cx + 0.2, 1.05}, {cx + 0.1, 1.05}};
        for (int n = 0; n < 6; ++n) REQUIRE(give(sim, from[n][0], from[n][1], cx - 0.01 + 0.004 * n, 1.04 + 0.004 * n));
    }
    const int face = sim.cell_holding(1.05, 1.05), beside = sim.cell_holding(1.35, 1.05);
    REQUIRE(put_own(sim, 1.3, 1.0, {{1.305, 1.02}, {1.307, 1.04}, {1.309, 1.06}, {1.311, 1.08}}) == 4);  // cell (13, 10)'s own, nearest its left edge
    sim.map_to_lattice();
    const std::vector<double> x0(p.x), y0(p.y);
    sim.step();
    int at_face = 0, at_beside = 0, moved = 0;
    for (std::size_t k = 0; k < p.size(); ++k) {
        at_face += p.cell[k] == face;
        at_beside += p.cell[k] == beside;
        if (p.x[k] == x0[k] && p.y[k] == y0[k]) continue;
        ++moved;
        CHECK(x0[k] >= 1.3);  // from the cell beside the wall's
        CHECK(p.x[k] >= 1.3);  // not into the wall's cells
    }
    MESSAGE("beside a wall: " << sim.shifted() << " moves; the cell on the face holds " << at_face << ", the one beside the wall's cells " << at_beside);
    CHECK(sim.shifted() == 2);
    CHECK(moved == 2);
    CHECK(at_face == 10);
    CHECK(at_beside == 8);
    CHECK(sim.parked() == 0);
}

// The guard's moves in the account: the scene above under gravity with a horizontal part
// (gx = 5, gy = -9.81 m/s^2, so that its horizontal moves change the potential energy), a
// free fall of the whole block, run beside the same without SHIFT: the two fall alike (no
// stress, every point the same increment) and differ after the step by the guard's moves
// alone, so w_shift is sum -m g . (x_with - x_without) and the potential energy of the run
// with SHIFT is the other's plus w_shift; energy_error stays at its rounding.
TEST_CASE("hard: SHIFT's guard puts the potential energy of its moves in w_shift") {
    for (const Cycle& cycle : kCycles) {
        Scene t = guard_block({0.5, 0.5, 1.5, 1.5}, 20, cycle);
        t.gravity_x = 5; t.gravity_y = -9.81;
        t.dt_s = 0.5 * stable_dt(t);
        Scene s = t;
        s.shift = false;
        REQUIRE(validate(t).empty());
        Simulation a(t), b(s);
        for (Simulation* sim : {&a, &b}) {
            int given = 0;
            for (const double fx : {0.95, 1.15})
                for (const double fy : {0.95, 1.05, 1.15}) {
                    REQUIRE(give(*sim, fx, fy, 1.04 + 0.004 * given, 1.045 + 0.002 * given));
                    ++given;
                }
            sim->map_to_lattice();
        }
        a.step();
        b.step();
        REQUIRE(a.shifted() == 2);
        const Points &p = a.points(), &q = b.points();
        double w = 0;
        for (std::size_t k = 0; k < p.size(); ++k) w += -a.point_mass(k) * (s.gravity_x * (p.x[k] - q.x[k]) + s.gravity_y * (p.y[k] - q.y[k]));
        const Simulation::Energy ea = a.energy(), eb = b.energy();
        MESSAGE(std::string(cycle.name) << ": w_shift " << ea.w_shift << " J/m, the moves' -m g . dx " << w
                << ", energy_error " << ea.error << " with, " << eb.error << " without");
        CHECK(std::fabs(w) > 1e-3);  // (a move of a few cm of 5 kg: not zero)
        CHECK(ea.w_shift == approx(w).epsilon(1e-9));
        CHECK(ea.gravity - eb.gravity == approx(ea.w_shift).epsilon(1e-6));
        CHECK(std::fabs(ea.error) < 1e-9);
    }
}

// A pass moves points only: mass, volume and (ADVECT FLIP) each point's own increment stay,
// so without gravity or supports the points' momentum sum_p m_p d_p, which FLIP's transfer
// keeps exactly, is kept through the passes too. Two cohesionless blocks thrown at each
// other at 5 m/s (the left one four times the right one's mass) crowd where they meet
// (ABOVE=1: from the first crowding).
TEST_CASE("hard: SHIFT keeps the momentum of two colliding blocks under ADVECT FLIP") {
    Scene s;
    s.mx = 50; s.my = 30; s.cell_m = 0.1;
    s.materials.push_back(Material::mohr(1, 1e7, 0.3, 2000, 30, 0));
    s.clusters.push_back({1, {1.5, 1.1, 2.3, 1.9}, 2, {}});
    s.clusters.push_back({1, {2.7, 1.3, 3.1, 1.7}, 2, {}});
    s.mapping = Mapping::Smooth; s.advect = Advect::Flip;
    s.shift = true; s.shift_above = 1;
    s.steps = 300;  // they meet after 0.04 s (78 steps), and all stay on the lattice
    s.dt_s = 0.5 * stable_dt(s);
    REQUIRE(validate(s).empty());
    Simulation sim(s);
    const Points& p = sim.points();
    auto momentum = [&](double& mx, double& my, double& scale) {
        mx = my = scale = 0;
        for (std::size_t k = 0; k < p.size(); ++k) {
            const double m = sim.point_mass(k);
            mx += m * p.flip_ux[k]; my += m * p.flip_uy[k];
            scale += m * std::hypot(p.flip_ux[k], p.flip_uy[k]);
        }
    };
    Points& w = sim.points();
    for (std::size_t k = 0; k < p.size(); ++k) w.flip_ux[k] = (p.x[k] < 2.5 ? 5.0 : -5.0) * s.dt_s;
    double mx0, my0, scale;
    momentum(mx0, my0, scale);
    REQUIRE(mx0 > 0.2 * scale);
    double worst = 0;
    for (long k = 0; k < s.steps; ++k) {
        sim.step();
        double mx, my, sc;
        momentum(mx, my, sc);
        worst = std::max({worst, std::fabs(mx - mx0) / scale, std::fabs(my - my0) / scale});
    }
    MESSAGE("two blocks colliding under ADVECT FLIP with SHIFT: " << sim.shifted() << " moves, momentum kept to " << worst << " of sum m |d|, packing " << sim.packing());
    CHECK(sim.shifted() > 0);
    CHECK(worst < 1e-12);
    CHECK(mass_exact(sim));
    CHECK(sim.mass_outflow() == 0);
}

// The passes wait for the first crowding past ABOVE: a scene that never crowds (the column
// at rest, the bouncing block whose cells gain at most a point's sliver) runs bit for bit
// as without the card.
TEST_CASE("hard: SHIFT changes nothing in a scene whose cells never hold more than ABOVE times their area") {
    for (const char* deck : {"decks/column.deck", "decks/drop.deck"}) {
        Scene s;
        REQUIRE(read_deck(deck, s).empty());
        s.outputs.clear();
        s.steps = std::min(s.steps, 3000L);
        Scene t = s;
        t.shift = true;
        Simulation a(s), b(t);
        for (long k = 0; k < s.steps; ++k) { a.step(); b.step(); }
        CHECK_MESSAGE(b.shifted() == 0, std::string(deck));
        CHECK_MESSAGE(a.points().x == b.points().x, std::string(deck));
        CHECK_MESSAGE(a.points().y == b.points().y, std::string(deck));
        CHECK_MESSAGE(a.points().syy == b.points().syy, std::string(deck));
        CHECK_MESSAGE(a.energy().error == b.energy().error, std::string(deck));
    }
}

// The account names what a pass changes: two runs of one scene, with SHIFT and without, are
// the same bits until the first pass (after step 10, ABOVE=1), so after it their points
// differ by the moves alone. Then w_shift is the potential energy those moves gave,
// sum_p -m_p g . (x_with - x_without), the potential energy of the run with SHIFT is the
// other's plus w_shift, and energy_error, which counts w_shift as work in, stays as small
// as the other run's (its scale grows with the potential energy: the two differ there; left
// out of the work in, w_shift would read as most of the energy in play). The upper half of
// a column is squeezed to 0.7 of its height before the first step, so that the pass has
// crowding to undo and its potential energy is a good part of the energy in play (to half
// or 0.55, the flow brings nine points into some cells within the first steps, and the
// guard moves them before the pass).
TEST_CASE("hard: SHIFT's w_shift is the potential energy its moves gave, and the account stays closed") {
    Scene s;
    REQUIRE(read_deck("decks/verify_collapse.deck", s).empty());
    s.outputs.clear();
    s.clusters[0].box.y1 = 2;
    refine(s, 3);
    Scene t = s;
    t.shift = true;
    t.shift_above = 1;
    t.shift_rate = 1;
    REQUIRE(validate(t).empty());
    Simulation a(t), b(s);
    for (Simulation* sim : {&a, &b}) {
        Points& p = sim->points();
        for (std::size_t k = 0; k < p.size(); ++k)
            if (p.y[k] > 1) { p.y[k] = 1 + 0.7 * (p.y[k] - 1); p.cell[k] = sim->cell_holding(p.x[k], p.y[k]); }
        sim->map_to_lattice();
    }
    for (int k = 0; k < 9; ++k) { a.step(); b.step(); }
    CHECK(a.shifted() == 0);
    CHECK(a.points().y == b.points().y);
    a.step();
    b.step();
    REQUIRE(a.shifted() > 0);
    const Points &p = a.points(), &q = b.points();
    REQUIRE(p.size() == q.size());
    double w = 0, moved = 0;
    for (std::size_t k = 0; k < p.size(); ++k) {
        REQUIRE(p.id[k] == q.id[k]);
        const double m = a.point_mass(k);
        w += -m * (s.gravity_x * (p.x[k] - q.x[k]) + s.gravity_y * (p.y[k] - q.y[k]));
        moved += m * std::fabs(s.gravity_y * (p.y[k] - q.y[k]));
    }
    const Simulation::Energy ea = a.energy(), eb = b.energy();
    MESSAGE("first pass: " << a.shifted() << " moves, w_shift " << ea.w_shift << " J/m (the sum of -m g . dx over the moves " << w << ", of |m g dy| " << moved
            << "), the potential energy " << ea.gravity << " with, " << eb.gravity << " without; energy_error " << ea.error << " with, " << eb.error << " without");
    CHECK(std::fabs(ea.w_shift) > 0.01 * moved);  // not a cancellation (7 % of it here): the 1e-9 below is not rounding
    CHECK(ea.w_shift == approx(w).epsilon(1e-9));
    CHECK(ea.gravity - eb.gravity == approx(ea.w_shift).epsilon(1e-6));
    CHECK(std::fabs(ea.error) <= 2 * std::fabs(eb.error));
    CHECK(std::fabs(ea.w_shift) > 0.5 * (ea.kinetic + std::fabs(ea.strain) + std::fabs(ea.gravity)));
}

// A pass does not carry points across a fixed cell edge: the hopper's bin with its lowest
// half metre squeezed to half its height against the floor (y = 1, fixed beside the slot),
// so that the crowding's gradient points into the floor; RATE=1, ABOVE=1. No point moves
// from above the floor to below it beside the slot (2.5 < x < 3.5 is the slot), in either
// cycle, and the passes did move points there.
TEST_CASE("hard: SHIFT moves no point across a fixed edge, crowded against it") {
    for (const bool flip : {false, true}) {
        Scene s;
        REQUIRE(read_deck("decks/verify_hopper.deck", s).empty());
        s.outputs.clear();
        s.shift = true; s.shift_above = 1; s.shift_rate = 1;
        s.reorder = 0;  // (the points by storage index, step to step)
        if (flip) { s.mapping = Mapping::Smooth; s.advect = Advect::Flip; }
        REQUIRE(validate(s).empty());
        Simulation sim(s);
        Points& p = sim.points();
        for (std::size_t k = 0; k < p.size(); ++k)
            if (p.y[k] < 1.5) { p.y[k] = 1 + 0.5 * (p.y[k] - 1); p.cell[k] = sim.cell_holding(p.x[k], p.y[k]); }
        sim.map_to_lattice();
        long crossed = 0, near = 0;
        for (long n = 0; n < 100; ++n) {
            std::vector<double> x0(p.x), y0(p.y);
            const std::vector<std::int32_t> id0(p.id);
            const long before = sim.shifted();
            sim.step();
            REQUIRE(p.id == id0);  // (no sort, and no point left in 100 steps)
            for (std::size_t k = 0; k < p.size(); ++k) {
                const bool beside = std::min(x0[k], p.x[k]) < 2.5 || std::max(x0[k], p.x[k]) > 3.5;
                if (beside && y0[k] >= 1 && p.y[k] < 1) ++crossed;
                if (sim.shifted() > before && beside && p.y[k] < 1.1 && p.y[k] != y0[k]) ++near;
            }
        }
        MESSAGE(std::string(flip ? "ADVECT FLIP" : "the paper's cycle") << ": " << sim.shifted() << " moves, " << crossed << " crossings of the floor beside the slot");
        CHECK(near > 0);  // points within a cell of the floor moved in pass steps
        CHECK(crossed == 0);
    }
}

// ADVECT FLIP beside an embedded wall that reaches out of the material. A heap at rest from
// the first step (GEOSTATIC); the wall stands in its base and rises past the heap's face,
// which lies on a cell edge: its points' squares end there, and the wall's first steps
// nudge the face outward by round-off. The wall drives the two lines of nodes either side
// of its material line, and their free relative motion is eq. 13 on the pair's masses
// (drive_embedded). Under FLIP those were the transfer's, of order s^2 in the width s of
// the sliver of squares in the cell beyond the face, against eq. 8's force of order s: the
// pair moved 0.3 m at step 4 and the run stopped. Now below 1 % of eq. 10's masses the pair
// takes eq. 10's: the run stays healthy and makes no energy. (FLIP's account loses 45 % of
// the little energy in play at step 2: the wall's start is an impact, whose change reaches
// the points through the weights; at the end 1.5e-4, the paper's cycle 1.9e-3.)
TEST_CASE("hard: ADVECT FLIP beside a wall reaching out of the material: a pair of sliver mass does not run away") {
    Scene s;
    REQUIRE(read_deck_text("GRID 8 6 0.5\n"
                           "MATERIAL 1 ELASTIC E=2E7 NU=0.25 RHO=2000\n"
                           "MATERIAL 2 MOHR E=5E7 NU=0.3 RHO=1900 PHI=35 C=1E3\n"
                           "CLUSTER 1 0 0 4 1\n"
                           "CLUSTER 2 0 1 2 2.5 PPC=3\n"
                           "FIX X 0 0 0 3\n"
                           "FIX XY 0 0 4 0\n"
                           "WALL 1 3 0.5 3 2.5 -0.1 0\n"
                           "GEOSTATIC\n"
                           "GRAVITY 0 -9.81\n"
                           "DAMPING 0.8\n"
                           "MAPPING SMOOTH\n"
                           "ADVECT FLIP\n"
                           "STEP 1E-4 2000\n",
                           "heap.deck", s)
                .empty());
    Simulation sim(s);
    bool healthy = true;
    double made = 0;  // the most energy the cycle made, as a fraction of the energy in play
    for (long n = 0; n < s.steps && healthy; ++n) {
        sim.step();
        healthy = sim.healthy();
        made = std::max(made, -sim.energy().error);
    }
    MESSAGE("ADVECT FLIP, heap beside a wall reaching out of it: healthy " << healthy << ", most energy made " << made << ", energy_error at the end " << sim.energy().error);
    CHECK(healthy);
    CHECK(made < 0.02);                           // no energy made (measured: none)
    CHECK(std::fabs(sim.energy().error) < 0.01);  // the start's impact loss diluted (measured 1.5e-4)
}
