// Moving walls (paper section 3) and the paper's experiments that use them or flow:
// the plane-strain compression test (Fig. 4) and the trapdoor (Fig. 6).
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "../lpfdm.hpp"
#include "common.hpp"

using namespace lpfdm;

namespace {

// An elastic block W x H on a rough base, smooth sides, a wall on its top line of nodes.
Scene confined_block(double vy) {
    Scene s;
    s.mx = 10; s.my = 24; s.cell_m = 0.1;
    s.materials.push_back(Material::elastic(1, 1e7, 0.3, 1000));
    s.clusters.push_back({1, {0, 0, 1, 2}, 2, {}});
    s.fixes.push_back({kFixX, {0, 0.05, 0, 1.95}, {}});  // smooth sides up to the wall
    s.fixes.push_back({kFixX, {1, 0.05, 1, 1.95}, {}});
    s.fixes.push_back({kFixX | kFixY, {0, 0, 1, 0}, {}});
    s.walls.push_back({1, {0, 2, 1, 2}, 0, vy, {}});  // the whole top line of nodes
    s.damping = 0.8; s.dt_s = 4e-4; s.steps = 1;
    return s;
}

}  // namespace

TEST_CASE("a wall's nodes move exactly as prescribed and pass to the next line after one cell") {
    Scene s = confined_block(0);
    s.walls[0].vy = -0.1 * s.cell_m / s.dt_s;  // a tenth of a cell per step: the allowed maximum
    s.damping = 0;
    REQUIRE(validate(s).empty());
    Simulation sim(s);
    const double du = s.walls[0].vy * s.dt_s;
    for (int n = 1; n <= 25; ++n) {
        sim.step();
        const int line = 20 - (n - 1) / 10;  // node row driven during step n
        for (int i = 0; i <= 10; ++i) CHECK(sim.du_y()[std::size_t(sim.node(i, line))] == du);
        for (int i = 0; i <= 10; ++i) CHECK(sim.du_x()[std::size_t(sim.node(i, line))] == 0.0);
        CHECK(sim.walls()[0].dy == approx(du * n).epsilon(1e-14));
        CHECK(sim.walls()[0].shift_j == -(n / 10));  // whole cells travelled after n increments
    }
}

TEST_CASE("confined elastic compression by a wall: force = M strain W, and equals the base reaction") {
    Scene s = confined_block(-0.005);
    s.steps = 1000;  // 0.4 s: 2 mm, a strain of 1e-3
    Simulation sim(s);
    const Material& m = s.materials[0];
    const double M = m.E * (1 - m.nu) / ((1 + m.nu) * (1 - 2 * m.nu)), W = 1, H = 2;
    for (long n = 0; n < s.steps; ++n) sim.step();
    const WallState& w = sim.walls()[0];
    const double strain = -w.dy / H;
    // Confined (oedometric) compression: one-dimensional, sigma_yy = M strain over W.
    const double expect = M * strain * W;
    MESSAGE("wall force " << -w.fy << " N/m, M strain W " << expect << " N/m (while moving)");
    CHECK(-w.fy == approx(expect).epsilon(0.02));
    sim.set_wall_velocity(1, 0, 0);  // hold the wall and let the column come to rest
    for (int n = 0; n < 3000; ++n) sim.step();
    MESSAGE("at rest: wall force " << -w.fy << " N/m, base reaction " << sim.reaction_y() << " N/m, ke " << sim.kinetic_energy());
    CHECK(-w.fy == approx(sim.reaction_y()).epsilon(1e-6));
    CHECK(-w.fy == approx(M * (-w.dy / H) * W).epsilon(0.02));
}

namespace {

struct Curve {
    std::vector<double> strain, q;  // axial strain, deviator stress [Pa]
    double band_left = 0, band_right = 0;  // shear-band inclinations from the horizontal [deg]
};

// The compression test of decks/psc.deck on 2 x 2 points per cell, to `strain` axial strain.
Curve compression(bool scatter_and_softening, double final_strain) {
    Scene s;
    REQUIRE(read_deck("decks/psc.deck", s).empty());
    for (auto& c : s.clusters) c.ppc = 2;
    if (!scatter_and_softening) { s.materials[0].scatter = 0; s.materials[0].soften = 0; }
    const double H = 0.2, W = 0.1;
    s.steps = long(final_strain * H / (-s.walls[0].vy) / s.dt_s);
    Simulation sim(s);
    Curve c;
    for (long n = 1; n <= s.steps; ++n) {
        sim.step();
        REQUIRE(sim.healthy());
        if (n % 200 == 0) { c.strain.push_back(-sim.walls()[0].dy / H); c.q.push_back(-sim.walls()[0].fy / W); }
    }
    // Shear bands: in each half of the specimen, the points whose plastic shear strain is in
    // the top 15 %; the band's direction is the principal axis of their positions (PCA).
    const Points& p = sim.points();
    std::vector<double> ep;
    for (std::size_t k = 0; k < p.size(); ++k) if (sim.material_id(k) == 1) ep.push_back(p.plastic_shear[k]);
    std::sort(ep.begin(), ep.end());
    const double cut = ep[std::size_t(0.85 * double(ep.size()))];
    for (int side = 0; side < 2; ++side) {
        double n = 0, mx = 0, my = 0, sxx = 0, syy = 0, sxy = 0;
        for (std::size_t k = 0; k < p.size(); ++k) {
            if (sim.material_id(k) != 1 || p.plastic_shear[k] < cut || (p.x[k] < 0.15) != (side == 0)) continue;
            n += 1; mx += p.x[k]; my += p.y[k];
        }
        if (n < 3) continue;
        mx /= n; my /= n;
        for (std::size_t k = 0; k < p.size(); ++k) {
            if (sim.material_id(k) != 1 || p.plastic_shear[k] < cut || (p.x[k] < 0.15) != (side == 0)) continue;
            sxx += (p.x[k] - mx) * (p.x[k] - mx); syy += (p.y[k] - my) * (p.y[k] - my); sxy += (p.x[k] - mx) * (p.y[k] - my);
        }
        const double angle = 0.5 * std::atan2(2 * sxy, sxx - syy) / kDeg;  // of the major axis
        (side == 0 ? c.band_left : c.band_right) = std::fabs(angle);
    }
    return c;
}

}  // namespace

TEST_CASE("compression test without scatter or softening peaks at 2c tan(45 + phi/2) within 5 % [slow]") {
    const Curve c = compression(false, 0.004);
    const double peak = *std::max_element(c.q.begin(), c.q.end());
    const double expect = 2 * 9800 * std::tan((45 + 28.648 / 2) * kDeg);
    MESSAGE("peak q = " << peak << " Pa, Mohr-Coulomb " << expect << " Pa (rough ends, wall impact 4 % of the peak)");
    CHECK(peak == approx(expect).epsilon(0.05));
    CHECK(c.q.back() == approx(expect).epsilon(0.05));  // perfectly plastic: a plateau
}

TEST_CASE("compression test with the paper's scatter and softening: a peak, then a drop; shear bands [slow]") {
    const Curve c = compression(true, 0.01);
    const auto top = std::max_element(c.q.begin(), c.q.end());
    const double peak = *top, last = c.q.back();
    const double intact = 2 * 9800 * std::tan((45 + 28.648 / 2) * kDeg);
    MESSAGE("peak q = " << peak << " Pa at strain " << c.strain[std::size_t(top - c.q.begin())] << ", at 1 % strain " << last
                        << " Pa; intact mean strength " << intact << " Pa");
    MESSAGE("shear bands (PCA of the 15 % most sheared points in each half): " << c.band_left << " and " << c.band_right
                        << " deg from the horizontal (minor stress axis); Coulomb 45 + phi/2 = 59.3, Roscoe 45 + psi/2 = 45");
    CHECK(c.band_left >= 0);          // measured and reported; at 1 % strain the bands are young
    CHECK(top != c.q.end() - 1);      // the peak is not the end of the curve
    CHECK(last < 0.9 * peak);         // softening after the peak
    CHECK(peak < 1.05 * intact);      // scatter and softening do not make it stronger
}

TEST_CASE("trapdoor: mass inside + outflow == initial at every step, outflow grows, values stay finite [slow]") {
    Scene s;
    REQUIRE(read_deck("decks/trapdoor.deck", s).empty());
    Simulation sim(s);
    double out_prev = 0;
    for (long n = 0; n < s.steps; ++n) {
        sim.step();
        REQUIRE(sim.healthy());
        REQUIRE(sim.mass_inside() + sim.mass_outflow() == sim.mass_initial());
        REQUIRE(sim.mass_outflow() >= out_prev);
        out_prev = sim.mass_outflow();
    }
    MESSAGE("trapdoor: " << sim.mass_outflow() << " kg/m left of " << sim.mass_initial() << " after " << sim.time() << " s");
    CHECK(sim.mass_outflow() > 0.005 * sim.mass_initial());
    CHECK(sim.first_nonfinite_point() == -1);
}

// Constraints that combine: a SMOOTH wall drives its column of nodes in x, the smooth base
// (FIX Y) holds its row in y, and they share the wall's lowest node. Written so, the deck
// the natural way: sand (c = 0, phi = 30, nu = 0.3) 8 m long and 4 m high between the
// wall at x = 2 m and a smooth far end, at rest: the thrust is K0 gamma H^2 / 2 with
// K0 = nu / (1 - nu) (a laterally confined elastic layer: no point yields), the scene at
// rest, the energy account closed. With both mappings.
TEST_CASE("a SMOOTH wall and the smooth base's FIX Y share a node: at rest the thrust is K0's within 3 %, with either mapping") {
    const std::string deck = "GRID 40 24 0.25\n"
                             "MATERIAL 1 MOHR E=2E7 NU=0.3 RHO=2000 PHI=30 C=0\n"
                             "CLUSTER 1 2 0 10 4\n"
                             "FIX Y 0 0 10 0\n"
                             "FIX X 10 0 10 6\n"
                             "WALL 1 2 0 2 4 0 0 SMOOTH\n"
                             "GRAVITY 0 -9.81\n"
                             "DAMPING 0.8\n"
                             "STEP 1E-3 3000\n";
    for (const Mapping mapping : {Mapping::Paper, Mapping::Smooth}) {
        Scene s;
        REQUIRE(read_deck_text(deck, "smooth_wall.deck", s).empty());
        s.mapping = mapping;
        Simulation sim(s);
        for (long n = 0; n < s.steps; ++n) sim.step();
        const double k0 = 0.3 / 0.7 * 2000 * 9.81 * 4 * 4 / 2;
        MESSAGE(std::string(mapping == Mapping::Paper ? "MAPPING PAPER" : "MAPPING SMOOTH") << ": thrust " << sim.walls()[0].fx << " N/m against K0's " << k0
                << ", unbalanced-force ratio " << sim.unbalanced_ratio() << ", energy_error " << sim.energy().error);
        CHECK(std::fabs(sim.walls()[0].fx) == approx(k0).epsilon(0.03));
        // The paper's mapping comes to rest to round-off (3e-11). MAPPING SMOOTH stays at
        // 4e-5 (at rest by the program's 1e-3, and so through 20 000 steps, the thrust then
        // 1.2 % below K0's) while energy_error drifts down, -2.9 % by 20 s: its rest is not
        // yet exact.
        CHECK(sim.unbalanced_ratio() < (mapping == Mapping::Paper ? 1e-6 : kAtRest));
        CHECK(std::fabs(sim.energy().error) < 0.01);
        CHECK(sim.mass_outflow() == 0);
        CHECK(sim.parked() == 0);  // the wall holds the material by its nodes: no point's move is clamped
    }
}

// The same sand with the wall's box starting 1 cm above the base (WALL 1 2 0.01 2 4): the
// node under the wall is held in y by the base only, free in x, and the sand carries it
// through the wall's face; the points that the lattice moves past the face are stopped on
// it (hold_by_walls) and pack the cell. parked() counts those stops: none in the deck
// above, thousands here, and more the longer it runs.
TEST_CASE("parked: the points a wall's face stops are counted; a face with a free node under it stops them by the thousand") {
    const std::string deck = "GRID 40 24 0.25\n"
                             "MATERIAL 1 MOHR E=2E7 NU=0.3 RHO=2000 PHI=30 C=0\n"
                             "CLUSTER 1 2 0 10 4\n"
                             "FIX Y 0 0 10 0\n"
                             "FIX X 10 0 10 6\n"
                             "WALL 1 2 0.01 2 4 0 0 SMOOTH\n"
                             "GRAVITY 0 -9.81\n"
                             "DAMPING 0.8\n"
                             "STEP 1E-3 3000\n";
    Scene s;
    REQUIRE(read_deck_text(deck, "free_node.deck", s).empty());
    Simulation sim(s);
    long at_half = 0;
    for (long n = 1; n <= s.steps; ++n) {
        sim.step();
        if (n == s.steps / 2) at_half = sim.parked();
    }
    MESSAGE("a wall with a free node under it: " << at_half << " moves clamped by step " << s.steps / 2 << ", " << sim.parked() << " by step " << s.steps);
    CHECK(at_half > 1000);
    CHECK(sim.parked() > at_half);
}
