// The energy account (Simulation::energy, the history's energy columns) against known
// answers: free fall (potential into kinetic, exactly), an undamped elastic column ringing
// under its own weight (conserved to the discretisation), confined compression by a wall
// (the wall's work into strain energy M eps^2 / 2 per unit volume), and plane-strain
// compression of Mohr-Coulomb soil (the wall's work dissipated by the plastic returns).
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>

#include "../lpfdm.hpp"
#include "common.hpp"

using namespace lpfdm;

namespace {

// The largest |energy_error| over the samples taken every `every` steps of `steps` steps.
double worst_error(Simulation& sim, long steps, long every) {
    double worst = 0;
    for (long n = 1; n <= steps; ++n) {
        sim.step();
        if (n % every == 0) worst = std::max(worst, std::fabs(sim.energy().error));
    }
    return worst;
}

// verify_psc.deck run 10 000 steps (0.24 s: 1.2 % axial strain, well past the peak at
// ~0.3 %): the account within 1 % at every sample, and once the specimen flows at its
// limit load nearly all the wall's work dissipated by plasticity (the elastic energy stays
// near its value at the peak). The account at the end.
Simulation::Energy psc_account(Simulation& sim, const char* how) {
    const double worst = worst_error(sim, 10000, 100);
    const Simulation::Energy e = sim.energy();
    MESSAGE("PSC" << std::string(how) << ": wall work " << e.w_walls << ", plastic " << e.d_plastic << ", strain " << e.strain << ", damping " << e.d_damping
                  << "; largest |energy_error| " << worst);
    CHECK(worst < 0.01);
    CHECK(e.d_plastic > 0.7 * e.w_walls);
    CHECK(e.d_plastic < e.w_walls);
    return e;
}

}  // namespace

// With either mapping: with MAPPING SMOOTH the block's squares cross five rows of cells on
// the way, and the nodes below it that only their edges reach (follow_material) fall with it.
TEST_CASE("energy: a free fall turns potential energy into kinetic energy, exactly") {
  for (const Mapping mapping : {Mapping::Paper, Mapping::Smooth}) {
    CAPTURE(int(mapping));
    Scene s;
    REQUIRE(read_deck("decks/freefall.deck", s).empty());
    s.mapping = mapping;
    Simulation sim(s);
    for (int n = 0; n < 2000; ++n) sim.step();  // 0.5 s: still in the air (contact at 0.608 s)
    const Simulation::Energy e = sim.energy();
    // The block of 2000 kg/m has fallen g t (t - dt) / 2 (see the deck): its potential
    // energy went down by m g times that, and the leapfrog's kinetic energy rose by as much.
    const double m = 2000, g = 9.81, t = 0.5, dt = 2.5e-4;
    const double fall = g * t * (t - dt) / 2;
    CHECK(e.gravity == approx(-m * g * fall).epsilon(1e-12));
    CHECK(e.kinetic == approx(m * g * fall).epsilon(1e-12));
    CHECK(e.w_gravity == approx(m * g * fall).epsilon(1e-12));
    // No stress while falling: the bound is the energy of a stress of 3e-4 Pa in M = 2.4e8 Pa;
    // rounding (an ulp of du over L a step, 2000 steps) leaves less than 1e-5 Pa.
    CHECK(std::fabs(e.strain) < 1e-20 * e.kinetic);
    CHECK(std::fabs(e.error) < 1e-12);  // rounding of 2000 steps' sums: 2000 x 1.1e-16 = 2e-13
  }
}

TEST_CASE("energy: an undamped elastic column ringing under its own weight keeps its energy") {
    Scene s;
    REQUIRE(read_deck("decks/verify_ringing.deck", s).empty());  // no damping, 1.4 s: four periods
    Simulation sim(s);
    const double worst = worst_error(sim, s.steps, 10);
    const Simulation::Energy e = sim.energy();
    MESSAGE("ringing column: largest |energy_error| " << worst << "; kinetic " << e.kinetic << ", strain " << e.strain << ", gravity " << e.gravity);
    // The points' potential energy and the nodes' gravity work differ by the mapping (the
    // points move by eq. 7a about node [1]); the error stays under a percent of the energy
    // in play (about 8 kJ/m) through four periods.
    CHECK(worst < 0.01);
    CHECK(e.w_walls == 0.0);
    CHECK(e.d_damping == 0.0);
    CHECK(e.d_plastic == 0.0);
    // Static answer at the mean of the oscillation: strain energy gamma^2 H^3 / (6 M) W.
    // Peak strain energy is four times the static one (twice the strain), reached every period.
}

TEST_CASE("energy: a wall's work in confined compression is the strain energy M eps^2 / 2 per unit volume") {
    Scene s;
    s.mx = 10; s.my = 24; s.cell_m = 0.1;
    s.materials.push_back(Material::elastic(1, 1e7, 0.3, 1000));
    s.clusters.push_back({1, {0, 0, 1, 2}, 2, {}});
    s.fixes.push_back({kFixX, {0, 0.05, 0, 1.95}, {}});  // smooth sides
    s.fixes.push_back({kFixX, {1, 0.05, 1, 1.95}, {}});
    s.fixes.push_back({kFixX | kFixY, {0, 0, 1, 0}, {}});  // rough base
    s.walls.push_back({1, {0, 2, 1, 2}, 0, -0.005, {}});  // the top line of nodes, down at 5 mm/s
    s.damping = 0.8; s.dt_s = 4e-4; s.steps = 1;
    Simulation sim(s);
    for (int n = 0; n < 1000; ++n) sim.step();  // 2 mm: a strain of 1e-3
    sim.set_wall_velocity(1, 0, 0);
    for (int n = 0; n < 3000; ++n) sim.step();  // at rest
    const Simulation::Energy e = sim.energy();
    const Material& m = s.materials[0];
    const double M = m.E * (1 - m.nu) / ((1 + m.nu) * (1 - 2 * m.nu)), W = 1, H = 2;
    const double eps = -sim.walls()[0].dy / H;
    MESSAGE("strain energy " << e.strain << " J/m, M eps^2 W H / 2 = " << 0.5 * M * eps * eps * W * H << "; wall work " << e.w_walls
                              << ", damping " << e.d_damping << ", error " << e.error);
    // Oedometric: sigma_yy = M eps everywhere (sigma_xx = sigma_zz = lambda eps), so the
    // elastic energy is M eps^2 / 2 per unit volume: 2 % covers the discretisation, as the
    // wall-force test of tests/test_walls.cpp.
    CHECK(e.strain == approx(0.5 * M * eps * eps * W * H).epsilon(0.02));
    // The wall did that work and what damping took: the account closes, to the order of the
    // strain (1e-3), as the stress does (eq. 8 divides by L^2, not by the points' volume).
    CHECK(e.w_walls == approx(e.strain + e.kinetic + e.d_damping).epsilon(1e-3));
    CHECK(std::fabs(e.error) < 1e-3);
    // The base and sides do not move: only the increments eq. 12 gives fixed nodes that
    // gained mass (and the supports take back) do work there. That correction is the step's
    // strain increment times the increment, second order: its work is at most about
    // v dt / H = 1e-6 of the wall's (an estimate of the largest it could be; 4e-10 measured:
    // the nodes that gain mass at the fixed edges are few).
    CHECK(std::fabs(e.w_fixes) < 1e-6 * e.w_walls);
}

TEST_CASE("energy: in plane-strain compression the wall's work goes into plastic dissipation") {
    Scene s;
    REQUIRE(read_deck("decks/verify_psc.deck", s).empty());
    Simulation sim(s);
    const Simulation::Energy e = psc_account(sim, "");
    // At the peak q = 2c tan(45 + phi/2) over the width W = 0.1 m, the work rate is q W v:
    // the dissipation of the last 100 steps matches the wall's force x its travel.
    const double d0 = e.d_plastic, w0 = e.w_walls, f0 = sim.walls()[0].fy;
    for (int n = 0; n < 500; ++n) sim.step();
    const Simulation::Energy e1 = sim.energy();
    const double travel = 500 * s.dt_s * 0.001;
    CHECK(e1.w_walls - w0 == approx(-0.5 * (f0 + sim.walls()[0].fy) * travel).epsilon(0.05));
    CHECK(e1.d_plastic - d0 == approx(e1.w_walls - w0).epsilon(0.05));
}

// ------------------------------------------------- ADVECT FLIP: the drop ---

namespace {

struct FlipDrop {
    double worst = 0;    // largest |energy_error| over the samples
    double rebound = 0;  // highest centroid after the first contact, over the drop (centroid heights above rest)
    double drift = 0;    // largest sideways move of the centroid [m]
    bool held = true;    // no point left the lattice or passed the floor
};

// An undamped elastic block 1 m x 1 m (n x n cells, 2 x 2 points each; E = 10 MPa,
// nu = 0.3) dropped 0.5 m onto a smooth floor (FIX Y) of a lattice 3 m x 2.5 m, with
// MAPPING SMOOTH and ADVECT FLIP, dt = frac of the stable limit, for 1.2 s (two bounces);
// its energy account read every 25 steps.
FlipDrop flip_drop(int n, double frac) {
    Scene s;
    s.mx = 3 * n; s.my = 5 * n / 2; s.cell_m = 1.0 / n;
    s.materials.push_back(Material::elastic(1, 1e7, 0.3, 2000));
    s.clusters.push_back({1, {1, 0.5, 2, 1.5}, 2, {}});
    s.fixes.push_back({kFixY, {0, 0, 3, 0}, {}});
    s.gravity_y = -9.81;
    s.damping = 0;
    s.mapping = Mapping::Smooth;
    s.advect = Advect::Flip;
    s.dt_s = frac * stable_dt(s);
    s.steps = long(1.2 / s.dt_s);
    REQUIRE(validate(s).empty());
    Simulation sim(s);
    const Points& p = sim.points();
    FlipDrop d;
    bool contact = false;
    for (long k = 1; k <= s.steps; ++k) {
        sim.step();
        double m = 0, cx = 0, cy = 0, ymin = 1e300;
        for (std::size_t q = 0; q < p.size(); ++q) {
            m += sim.point_mass(q); cx += sim.point_mass(q) * p.x[q]; cy += sim.point_mass(q) * p.y[q];
            ymin = std::min(ymin, p.y[q]);
        }
        cx /= m; cy /= m;
        d.drift = std::max(d.drift, std::fabs(cx - 1.5));
        d.held = d.held && ymin > 0;
        contact = contact || ymin < s.cell_m;
        if (contact) d.rebound = std::max(d.rebound, (cy - 0.5) / (1.0 - 0.5));
        if (k % 25 == 0) d.worst = std::max(d.worst, std::fabs(sim.energy().error));
    }
    d.held = d.held && sim.mass_outflow() == 0 && p.size() == std::size_t(4 * n * n);
    MESSAGE("ADVECT FLIP drop, " << n << " cells across, dt " << frac << " of the limit: largest |energy_error| " << d.worst
                                 << ", rebound " << d.rebound << " of the drop, drift " << d.drift << " m");
    return d;
}

void check_flip_drop(const FlipDrop& d) {
    CHECK(d.held);
    // The bound: the account closes within 1 % at every sample (the scheme's own
    // error, measured: 0.01-0.11 %, growing with n as more of the block rings).
    CHECK(d.worst < 0.01);
    CHECK(d.rebound > 0.5);   // it bounces ...
    CHECK(d.rebound <= 1.0);  // ... and gains no height
    CHECK(d.drift < 1e-3);    // a mirror-symmetric scene stays symmetric (round-off: 1e-14 m)
}

}  // namespace

// Eq. 12 loses or makes 10-57 % of this drop's energy (tests/README.md); ADVECT FLIP
// carries the increments on the points and keeps it.
TEST_CASE("energy: ADVECT FLIP keeps a dropped elastic block's energy within 1 % at every sample, 4 and 8 cells across") {
    for (const int n : {4, 8}) check_flip_drop(flip_drop(n, 0.49));
}

// The finer blocks and the shorter step: about a minute, run by make verify (the case
// above checks the same bounds at 4 and 8 cells in make test).
TEST_CASE("energy: ADVECT FLIP keeps a dropped elastic block's energy within 1 % at every sample, 4 to 32 cells across, two steps [slow][verify]") {
    for (const int n : {4, 8, 16, 32})
        for (const double frac : {0.16, 0.49}) {
            if (frac == 0.49 && n <= 8) continue;  // the case above
            check_flip_drop(flip_drop(n, frac));
        }
}

// ADVECT FLIP with one point a cell: a centred point's square is its cell, a quarter of
// its weight at each corner, so a checkerboard of the points' increments (+d, -d, ...)
// sums to nothing at every node. Neither the lattice nor eq. 14 sees it; as the points
// move their weights change and it feeds the lattice again. column.deck (damped, elastic)
// with 2 x 2 points comes to rest (unbalanced ratio 3e-6 at 6000 steps, the nodes'
// kinetic energy 4e-10 J/m), with one it never does (0.011-0.012 from step 4000 on, 8e-5
// J/m). The ratio after 6000 steps: below 1e-4 with two, above 1e-3 with one (the deck's
// warning says so; should a cure come, this test says the warning can go).
TEST_CASE("energy: ADVECT FLIP with one point a cell does not come to rest; with 2 x 2 it does") {
    auto last_ratio = [](int ppc) {
        Scene s;
        REQUIRE(read_deck("decks/column.deck", s).empty());
        s.clusters[0].ppc = ppc;
        s.mapping = Mapping::Smooth; s.advect = Advect::Flip;
        s.outputs.clear();
        REQUIRE(validate(s).empty());
        Simulation sim(s);
        for (long n = 0; n < s.steps; ++n) sim.step();
        return sim.unbalanced_ratio();
    };
    const double one = last_ratio(1), two = last_ratio(2);
    MESSAGE("column.deck with ADVECT FLIP: unbalanced ratio after 6000 steps " << one << " (PPC=1), " << two << " (PPC=2)");
    CHECK(two < 1e-4);
    CHECK(one > 1e-3);
}

// ------------------------------------------------- ADVECT FLIP: walls ---

namespace {

// The confined column above (1 m x 2 m, smooth sides, rough base) compressed by its top
// line of nodes, a wall moving down at 5 mm/s for 1000 steps (a strain of 1e-3) and then
// held, without damping: the column rings. With MAPPING SMOOTH and `advect`; the largest
// |energy_error| every 10 steps, and the account at the end.
double undamped_confined(Advect advect, Simulation::Energy& e) {
    Scene s;
    s.mx = 10; s.my = 24; s.cell_m = 0.1;
    s.materials.push_back(Material::elastic(1, 1e7, 0.3, 1000));
    s.clusters.push_back({1, {0, 0, 1, 2}, 2, {}});
    s.fixes.push_back({kFixX, {0, 0.05, 0, 1.95}, {}});
    s.fixes.push_back({kFixX, {1, 0.05, 1, 1.95}, {}});
    s.fixes.push_back({kFixX | kFixY, {0, 0, 1, 0}, {}});
    s.walls.push_back({1, {0, 2, 1, 2}, 0, -0.005, {}});
    s.damping = 0; s.dt_s = 4e-4; s.steps = 1;
    s.mapping = Mapping::Smooth; s.advect = advect;
    REQUIRE(validate(s).empty());
    Simulation sim(s);
    double worst = worst_error(sim, 1000, 10);
    sim.set_wall_velocity(1, 0, 0);
    worst = std::max(worst, worst_error(sim, 3000, 10));
    if (advect == Advect::Flip) {  // the impact's loss, every sample
        Simulation again(s);
        for (long n = 1; n <= 1000; ++n) {
            again.step();
            const Simulation::Energy a = again.energy();
            CHECK(std::fabs(a.w_walls - a.strain - a.kinetic) < 0.5 * 1000 * 1 * 0.1 * 0.005 * 0.005);
        }
    }
    e = sim.energy();
    return worst;
}

}  // namespace

// The wall's work goes into strain and kinetic energy and nowhere else (an undamped
// elastic run with a wall). With ADVECT FLIP but for its start: the wall takes its nodes
// at 5 mm/s from rest and the points there take that change through the transfer's
// weights, an impact, which loses at most the kinetic energy it gives them: m v^2 / 2 for
// the material of the top cell row, rho W L v^2 / 2 = 1.25e-3 J/m (measured: 2.3e-4 J/m
// lost, 28 % of the work done by then; the account within 1 % from the 22nd step on).
TEST_CASE("energy: ADVECT FLIP, a wall compressing an undamped elastic column: its work is the strain and kinetic energy but its start's impact [slow]") {
    Simulation::Energy f, q;
    const double flip = undamped_confined(Advect::Flip, f), eq12 = undamped_confined(Advect::Eq12, q);
    MESSAGE("undamped confined compression: largest |energy_error| " << flip << " (ADVECT FLIP), " << eq12 << " (eq. 12); FLIP's wall work "
            << f.w_walls << " J/m, strain " << f.strain << ", kinetic " << f.kinetic << ", the slip where the wall stopped " << f.d_slip
            << ", energy_error at the end " << f.error);
    CHECK(eq12 < 0.01);
    CHECK(f.w_walls > 0);
    CHECK(f.d_damping == 0.0);
    CHECK(std::fabs(f.w_fixes) < 1e-9 * f.w_walls);  // the fixed directions hold still: b = c = 0 there
    // The oedometric strain energy M eps^2 / 2 per unit volume, 1/2 x 1e-3^2 x 1.35e7 x
    // 2 m^2 = 13.5 J/m, within the 2 % of the damped test above; the account at the end
    // within the impact's loss.
    const double M = 1e7 * 0.7 / (1.3 * 0.4), impact = 0.5 * 1000 * 1 * 0.1 * 0.005 * 0.005;
    CHECK(f.strain == approx(0.5 * M * 1e-6 * 2).epsilon(0.02));
    CHECK(std::fabs(f.w_walls - f.strain - f.kinetic) < impact);
    CHECK(std::fabs(f.error) < 1e-3);
}

// verify_psc.deck with MAPPING SMOOTH and ADVECT FLIP: the account closes within 1 % at
// every sample and the wall's work goes into plastic dissipation, as with eq. 12 above.
TEST_CASE("energy: ADVECT FLIP, plane-strain compression: the wall's work into plastic dissipation, the account within 1 % [slow]") {
    Scene s;
    REQUIRE(read_deck("decks/verify_psc.deck", s).empty());
    s.mapping = Mapping::Smooth; s.advect = Advect::Flip;
    REQUIRE(validate(s).empty());
    Simulation sim(s);
    psc_account(sim, " with ADVECT FLIP");
}
