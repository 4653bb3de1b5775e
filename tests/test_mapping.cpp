// Large deformation: MAPPING SMOOTH (a point's contributions vary continuously as it
// crosses a cell edge), walls that hold (no point crosses a wall's face, the reported
// force is the force on the material), the FIX reactions, and mirror symmetry.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "../lpfdm.hpp"
#include "common.hpp"

using namespace lpfdm;

TEST_CASE("square_overlap: fractions that sum to one, change continuously across an edge, and mirror") {
    const double L = 0.25, l = L / 4;  // PPC 2
    const int m = 8;
    int a = 0;
    double w[2], c[2];
    square_overlap(0.1, l, L, m, a, w, c);  // the square [0.0375, 0.1625] lies in cell 0
    CHECK(a == 0);
    CHECK(w[0] == 1.0);
    CHECK(w[1] == 0.0);
    CHECK(c[0] == 0.1);
    // Across the edge at x = 0.25 the fraction in the left cell falls linearly from 1 to 0.
    double prev = 1;
    for (double x = 0.25 - l; x <= 0.25 + l; x += l / 50) {
        square_overlap(x, l, L, m, a, w, c);
        const double left = a == 0 ? w[0] : 0.0;
        CHECK(w[0] + w[1] == approx(1.0).epsilon(1e-15));
        // A step of l/50 moves 1/100 of the square, to the rounding of x's steps (half an ulp
        // of 0.25, 2.8e-17 m, 2e-16 of the square's width 2l, a few of them over the 100 steps);
        // 1e-12 is the same bound as the fraction's own check below.
        CHECK(std::fabs(left - prev) <= 1.0 / 100 + 1e-12);
        CHECK(left == approx(std::clamp((0.25 - (x - l)) / (2 * l), 0.0, 1.0)).epsilon(1e-12));
        prev = left;
    }
    // Mirrored about the middle of the lattice (x -> 2 - x), the fractions swap.
    const double x = 0.27;
    int b = 0;
    double v[2], d[2];
    square_overlap(x, l, L, m, a, w, c);
    square_overlap(m * L - x, l, L, m, b, v, d);
    CHECK(a + b == m - 2);
    CHECK(w[0] == approx(v[1]).epsilon(1e-14));
    CHECK(w[1] == approx(v[0]).epsilon(1e-14));
    CHECK(c[0] == approx(m * L - d[1]).epsilon(1e-14));
    // At the lattice's edges the part outside is left out.
    square_overlap(0.01, l, L, m, a, w, c);
    CHECK(a == 0);
    CHECK(w[0] == 1.0);
    square_overlap(m * L - 0.01, l, L, m, a, w, c);
    CHECK(a == m - 1);
    CHECK(w[0] == 1.0);
}

// MAPPING SMOOTH takes a point's strain and motion one axis at a time (smooth_strain): each
// node's weight is the mean over the square of its linear shape function (axis_shape),
// which must be the sum over the square's parts of their fractions times the shape
// function at each part's centre (GIMP's weight), sum to one, and reproduce a linear
// field exactly: the mean of x over the square is its centre.
TEST_CASE("axis_shape: GIMP's weights of a square's nodes, by quadrature, summing to one, reproducing x") {
    const double L = 0.25;
    const int m = 8;
    for (const double l : {L / 4, L / 6, L / 2}) {  // PPC 2, 3, 1
        for (int s = 0; s <= 400; ++s) {
            const double x = 0.001 + s * (m * L - 0.002) / 400;
            int a = 0;
            double w[2], c[2], S[3];
            square_overlap(x, l, L, m, a, w, c);
            detail::axis_shape(a, w, c, L, 1 / L, S);
            // The mean over the square (its part inside the lattice) of node a + n's hat
            // function, by the midpoint rule on 4000 slices (the hats are linear between
            // nodes: the rule is exact but at the one slice holding a node, 1e-7 at most).
            const double lo = std::max(0.0, x - l), hi = std::min(m * L, x + l);
            double q[3] = {0, 0, 0};
            const int slices = 4000;
            for (int k = 0; k < slices; ++k) {
                const double y = lo + (k + 0.5) * (hi - lo) / slices;
                for (int n = 0; n < 3; ++n) q[n] += std::max(0.0, 1 - std::fabs(y / L - (a + n))) / slices;
            }
            for (int n = 0; n < 3; ++n) CHECK(std::fabs(S[n] - q[n]) <= 1e-6);
            CHECK(S[0] + S[1] + S[2] == approx(1.0).epsilon(1e-14));
            // A square cut by the lattice's edge is the part inside: its centre is that part's.
            CHECK((S[0] * a + S[1] * (a + 1) + S[2] * (a + 2)) * L == approx(0.5 * (lo + hi)).epsilon(1e-13));
        }
    }
}

namespace {

// A point's mass in cell 0 of a 2 x 1 lattice, the point (PPC 1: the whole cell's square)
// placed at x.
double mass_left(Mapping mapping, double x) {
    Scene s;
    s.mx = 2; s.my = 1; s.cell_m = 1;
    s.materials.push_back(Material::elastic(1, 1e7, 0.3, 1000));
    s.clusters.push_back({1, {0, 0, 1, 1}, 1, {}});
    s.fixes.push_back({kFixX | kFixY, {0, 0, 2, 0}, {}});
    s.dt_s = 1e-4; s.steps = 1;
    s.mapping = mapping;
    Simulation sim(s);
    sim.points().x[0] = x;
    sim.points().cell[0] = x < 1 ? 0 : 1;
    sim.map_to_lattice();
    return sim.cell_mass()[0];
}

}  // namespace

TEST_CASE("MAPPING SMOOTH: a point's mass passes to the next cell continuously; the paper's jumps") {
    const double m = 1000;  // rho L^2, PPC 1
    for (double x : {0.9, 0.99, 0.999, 1.001, 1.01, 1.1}) {
        CHECK(mass_left(Mapping::Smooth, x) == approx(m * std::clamp(1.5 - x, 0.0, 1.0)).epsilon(1e-12));
        CHECK(mass_left(Mapping::Paper, x) == (x < 1 ? m : 0.0));
    }
}

namespace {

// Plane-strain compression without gravity: Mohr-Coulomb c = 15 kPa, phi = 20 deg,
// specimen 4 m x 8 m on a rough base under a stiff elastic cap driven down by a wall
// embedded in it; L = 0.5 m / K, PPC 2. q = 2 c tan(45 + phi/2) = 42.84 kPa. The wall
// moves at `speed` (0.01 m/s at L = 0.5 m): the difference between wall and base is the
// specimen's inertia and damping, and at 0.02 m/s it reaches 3.2 % while the bands form
// (2.5 % at 0.01 m/s; at L = 0.25 m, 6.0 %, 3.6 % and 2.1 % at 0.02, 0.01 and 0.005 m/s:
// tests/README.md). dt: 5e-4 s at L = 0.5 m, 2.8e-4 s at 0.25 m (0.79 and 0.89 of the
// cap's limit, L sqrt(rho / ((M + lambda)(1 + alpha))) = 6.3e-4 and 3.2e-4 s). At L = 0.5 m
// dt was 3e-4 s; 5e-4 s takes 60 % of the steps and moves SMOOTH's and FLIP's readings by
// less than 0.1 % of q (SMOOTH's worst wall against base 2.42 %, FLIP's 1.75 %, its wall's
// peak 1.029 q), the paper mapping's base at 3.75 % strain from 0.86 to 0.87 q.
// A sample every 200 steps.
struct Compression {
    std::vector<double> strain, wall, base;  // axial strain, wall force and base reaction per width [Pa]
};
Compression compress(Mapping mapping, double travel, int K = 1, double speed = 0.01, Advect advect = Advect::Eq12) {
    Scene s;
    s.mx = 16 * K; s.my = 20 * K; s.cell_m = 0.5 / K;
    s.materials.push_back(Material::mohr(1, 5e7, 0.3, 2000, 20, 15000));
    s.materials.push_back(Material::elastic(2, 5e8, 0.2, 2000));
    s.clusters.push_back({1, {2, 0, 6, 8}, 2, {}});
    s.clusters.push_back({2, {2, 8, 6, 9}, 2, {}});  // the cap, two cells
    s.fixes.push_back({kFixX | kFixY, {2, 0, 6, 0}, {}});
    s.walls.push_back({1, {2, 8.5, 6, 8.5}, 0, -speed, {}});
    s.damping = 0.8; s.dt_s = K == 1 ? 5e-4 : 2.8e-4; s.steps = 1;
    s.mapping = mapping; s.advect = advect;
    REQUIRE(validate(s).empty());
    Simulation sim(s);
    Compression c;
    const long steps = long(travel / speed / s.dt_s);
    for (long n = 1; n <= steps; ++n) {
        sim.step();
        if (n % 200) continue;
        c.strain.push_back(-sim.walls()[0].dy / 8);
        c.wall.push_back(-sim.walls()[0].fy / 4);
        c.base.push_back(sim.reaction_y() / 4);
    }
    return c;
}

}  // namespace

TEST_CASE("MAPPING SMOOTH: without gravity the wall's force equals the base reaction at every sample [slow]") {
    // 0.3 m of travel (3.75 % strain): the cap's points cross the wall's line of nodes.
    const double q = 2 * 15000 * std::tan((45 + 10) * 3.14159265358979323846 / 180);
    auto worst_after = [](const Compression& c, double from) {
        double worst = 0;
        for (std::size_t k = 0; k < c.strain.size(); ++k)
            if (c.strain[k] >= from) worst = std::max(worst, std::fabs(c.wall[k] / c.base[k] - 1));
        return worst;
    };
    const Compression c = compress(Mapping::Smooth, 0.3), p = compress(Mapping::Paper, 0.3);
    const double smooth = worst_after(c, 0.005), paper = worst_after(p, 0.005);
    double plateau_smooth = 0, plateau_paper = 0;  // the base reaction at the end
    plateau_smooth = c.base.back() / q;
    plateau_paper = p.base.back() / q;
    MESSAGE("after 0.5 % strain |wall / base - 1| at most " << smooth << " (SMOOTH), " << paper << " (PAPER); base at 3.75 % strain "
                                                           << plateau_smooth << " q (SMOOTH), " << plateau_paper << " q (PAPER)");
    CHECK(smooth < 0.03);
    CHECK(paper > 0.1);  // the spikes SMOOTH removes: the cap's points crossing the wall's line
    // The perfectly plastic specimen holds q on its plateau (8 cells across the specimen).
    CHECK(plateau_smooth == approx(1).epsilon(0.03));
    // The paper's mapping does not. Its base reads q within 0.1 % up to 2.8 % strain; then
    // the bulging sides' outermost points cross into the next column of cells, which they
    // only partly fill, and eq. 8 spreads their V sigma over the whole cell (max(L^2, sum V)):
    // 0.99 q at 3.1 %, 0.91 q at 3.4 %, 0.86 q at 3.75 %. This check read "within 10 % of
    // q" and passed only through doctest's scale, which doubled that tolerance near 1
    // (see approx in common.hpp).
    CHECK(plateau_paper < 0.95);
    CHECK(plateau_paper > 0.75);  // still most of q: the outer cells' loss, not a failure of the specimen
}

// The same compression on a lattice twice as fine (L = 0.25 m, 16 cells across the
// specimen, 2 304 points), the wall at 0.005 m/s (at 0.01 m/s the specimen's inertia
// while the bands form leaves 3.6 %, see above). The cap's rows of points (two per cell)
// cross lines of nodes after 0.78 % strain and every 1.56 % after that, where the
// paper's mapping makes its spikes. The bound on wall against base is the same 3 % as at
// L = 0.5 m; the peak is read from the wall itself (what Fig. 4 of the paper reads),
// within 3 % of q, the bound the compression must meet; the wall's overshoot is the
// specimen's inertia and damping, which fall with the wall's speed.
// Measured: at most 2.07 % (at 1.75 % strain), the wall's peak 1.026 q (0.4 % inside the
// bound), the base's 1.007 q; with ADVECT FLIP at most 2.95 % (at 2.15 % strain), the
// wall's peak 1.034 q over the run (1.033 q after 0.5 % strain), the base's 1.007 q.
// About two and a half minutes, both transfers: run by make verify (the cases above and
// below check the same bounds at L = 0.5 m in make test).
TEST_CASE("MAPPING SMOOTH at L = 0.25 m, with eq. 12 and with ADVECT FLIP: the wall reads the base reaction within 3 % at every sample, the base's peak q within 3 % [slow][verify]") {
    const double q = 2 * 15000 * std::tan((45 + 10) * 3.14159265358979323846 / 180);
    for (const Advect advect : {Advect::Eq12, Advect::Flip}) {
        const Compression c = compress(Mapping::Smooth, 0.3, 2, 0.005, advect);
        double worst = 0, at = 0, peak_wall = 0, peak_after = 0, peak_base = 0;
        for (std::size_t k = 0; k < c.strain.size(); ++k) {
            peak_wall = std::max(peak_wall, c.wall[k]);
            peak_base = std::max(peak_base, c.base[k]);
            if (c.strain[k] < 0.005) continue;
            const double d = std::fabs(c.wall[k] / c.base[k] - 1);
            if (d > worst) { worst = d; at = c.strain[k]; }
            peak_after = std::max(peak_after, c.wall[k]);
        }
        MESSAGE(std::string(advect == Advect::Flip ? "ADVECT FLIP" : "eq. 12") << ", L = 0.25 m: after 0.5 % strain |wall / base - 1| at most " << worst << " (at " << at * 100
                << " % strain); peak wall " << peak_wall / q << " q (" << peak_after / q << " q after 0.5 % strain), peak base " << peak_base / q << " q, "
                << c.strain.size() << " samples to " << c.strain.back() * 100 << " % strain");
        REQUIRE(c.strain.size() > 1000);
        CHECK(c.strain.back() > 0.037);
        CHECK(worst < 0.03);
        CHECK(peak_base == approx(q).epsilon(0.03));
        // The wall also carries eq. 14's drag on the vibrating flow, which under FLIP is
        // twice SMOOTH's (tests/README.md, the compression's plateau): its peak, 1.033 q
        // after 0.5 % strain, is bounded by the two checks above, not held to 3 % of q.
        if (advect == Advect::Eq12) CHECK(peak_wall == approx(q).epsilon(0.03));
    }
}

// The same compression with ADVECT FLIP (L = 0.5 m, the wall at 5 mm/s): the wall's nodes
// move with it and the points take the wall's changes only (flip_transfer). The bounds of
// eq. 12's: after 0.5 % strain the wall within 3 % of the base and of q, and the base's
// plateau and peak within 3 % of q. The wall's overshoot is the specimen's inertia, which
// FLIP does not take away in the transfer: at 0.01 m/s the wall read 1.035 q after 0.5 %
// strain (1.062 q before); at 5 mm/s measured 1.029 q, the base 1.013 q, wall against
// base 1.6 %. About a minute.
TEST_CASE("ADVECT FLIP: without gravity the wall's force equals the base reaction; the base holds q [slow]") {
    const double q = 2 * 15000 * std::tan((45 + 10) * 3.14159265358979323846 / 180);
    const Compression c = compress(Mapping::Smooth, 0.3, 1, 0.005, Advect::Flip);
    double worst = 0, peak_wall = 0, peak_after = 0, peak_base = 0;
    for (std::size_t k = 0; k < c.strain.size(); ++k) {
        peak_wall = std::max(peak_wall, c.wall[k]);
        peak_base = std::max(peak_base, c.base[k]);
        if (c.strain[k] < 0.005) continue;
        worst = std::max(worst, std::fabs(c.wall[k] / c.base[k] - 1));
        peak_after = std::max(peak_after, c.wall[k]);
    }
    MESSAGE("ADVECT FLIP: after 0.5 % strain |wall / base - 1| at most " << worst << ", the wall's peak " << peak_after / q << " q; base at "
            << c.strain.back() * 100 << " % strain " << c.base.back() / q << " q, its peak " << peak_base / q << " q; the wall's peak over the whole run "
            << peak_wall / q << " q");
    CHECK(c.strain.back() > 0.037);
    CHECK(worst < 0.03);
    CHECK(peak_after == approx(q).epsilon(0.03));
    CHECK(c.base.back() == approx(q).epsilon(0.03));
    CHECK(peak_base == approx(q).epsilon(0.03));
}

// A point whose square reaches past a free surface into a cell that holds nothing else:
// the two nodes beyond have only its little mass and no support. With eq. 5's one
// gradient per cell their equilibrium asked the point for sigma = 0, so a loaded free
// surface shed its stress (verify_psc.deck read q 13 % low); with the gradient at the
// part's centre (GIMP's) it asks only for zero traction across the surface.
TEST_CASE("MAPPING SMOOTH: a free surface of a compressed specimen keeps its load; verify_psc's plateau within 3 % of q") {
    Scene s;
    REQUIRE(read_deck("decks/verify_psc.deck", s).empty());
    s.mapping = Mapping::Smooth;
    Simulation sim(s);
    const double q = 2 * 9800 * std::tan((45 + 28.648 / 2) * kPi / 180);
    double sum = 0;
    long n = 0;
    for (long k = 1; k <= s.steps; ++k) {
        sim.step();
        if (-sim.walls()[0].dy < 0.00015 || k % 100) continue;  // the plateau: 0.075 % to 0.15 % strain
        sum += -sim.walls()[0].fy / 0.1;
        ++n;
    }
    const double plateau = sum / double(n);
    // The outermost column of points: their axial stress against the middle column's.
    const Points& p = sim.points();
    double edge = 0, middle = 0;
    long ne = 0, nm = 0;
    for (std::size_t k = 0; k < p.size(); ++k) {
        if (p.x[k] < 0.05) { edge += p.syy[k]; ++ne; }
        if (std::fabs(p.x[k] - 0.09) < 0.006) { middle += p.syy[k]; ++nm; }
    }
    edge /= double(ne); middle /= double(nm);
    MESSAGE("verify_psc with MAPPING SMOOTH: plateau " << plateau / q << " q; mean sigma_yy of the outermost points " << edge
                                                       << " Pa, of the middle ones " << middle << " Pa");
    CHECK(plateau == approx(q).epsilon(0.03));
    CHECK(edge == approx(middle).epsilon(0.25));
}

namespace {

// verify_psc.deck's plateau (the wall's travel past 0.15 mm, read every 100 steps): the
// mean of the wall's force and of the base reaction, per metre of the specimen's width.
struct Plateau { double wall = 0, base = 0; };
Plateau psc_plateau(Mapping mapping, Advect advect, int by, double window) {
    Scene s;
    REQUIRE(read_deck("decks/verify_psc.deck", s).empty());
    s.mapping = mapping; s.advect = advect; s.damping_window = window;
    if (by > 1) refine(s, by);
    REQUIRE(validate(s).empty());
    Simulation sim(s);
    Plateau p;
    long n = 0;
    for (long k = 1; k <= s.steps; ++k) {
        sim.step();
        if (-sim.walls()[0].dy < 0.00015 || k % 100) continue;
        p.wall += -sim.walls()[0].fy / 0.1;
        p.base += sim.reaction_y() / 0.1;
        ++n;
    }
    REQUIRE(n > 10);
    p.wall /= double(n); p.base /= double(n);
    return p;
}

}  // namespace

// DAMPING WINDOW (damped_increment): eq. 14 taken about each node's mean motion. With eq.
// 14 about rest, a specimen compressed at a constant speed vibrates while it flows, its
// nodes never reverse, and the damping holds back the flow at every step: the wall reads
// the base reaction plus that drag (at 10 cells 3.1 % with MAPPING SMOOTH, 1.4 % with the
// paper's mapping). About the mean, the window 2.4 ms (above the lattice's slowest elastic
// period 4 W / c_p = 2.1 ms), the wall equals the base and MAPPING SMOOTH's plateau is q.
// Measured: SMOOTH 0.9966 and 1.0009 q at 5 and 10 cells (0.9981 at 20), wall over base
// -1e-5 to 1e-5; the paper's mapping 0.9958 and 0.9636 q (its plateau about rest, +0.25 %
// at 10 cells, was the drag making up for a specimen 3.6 % weak).
TEST_CASE("DAMPING WINDOW: a flowing specimen's wall reads its base reaction; verify_psc's plateau within 1 % of q with MAPPING SMOOTH at 5 and 10 cells [slow]") {
    const double q = 2 * 9800 * std::tan((45 + 28.648 / 2) * kPi / 180);
    for (const int by : {1, 2}) {
        const Plateau sm = psc_plateau(Mapping::Smooth, Advect::Eq12, by, 2.4e-3), pa = psc_plateau(Mapping::Paper, Advect::Eq12, by, 2.4e-3);
        MESSAGE((5 * by) << " cells: MAPPING SMOOTH wall " << sm.wall / q << " q, base " << sm.base / q << " q; the paper's mapping wall " << pa.wall / q << " q, base "
                       << pa.base / q << " q");
        CHECK(sm.wall == approx(q).epsilon(0.01));
        CHECK(sm.wall == approx(sm.base).epsilon(1e-3));
        CHECK(pa.wall == approx(pa.base).epsilon(1e-3));
    }
}

// The finer rungs (make verify): MAPPING SMOOTH at 20 cells (measured 0.9981 q), and with
// ADVECT FLIP at 10 and 20 cells (1.0036 and 0.9942 q; at 5 cells 1.020 q, outside 1 %).
// About 45 s.
TEST_CASE("DAMPING WINDOW: verify_psc's plateau within 1 % of q with MAPPING SMOOTH at 20 cells, with ADVECT FLIP at 10 and 20 [slow][verify]") {
    const double q = 2 * 9800 * std::tan((45 + 28.648 / 2) * kPi / 180);
    const Plateau sm = psc_plateau(Mapping::Smooth, Advect::Eq12, 4, 2.4e-3);
    MESSAGE("20 cells: MAPPING SMOOTH wall " << sm.wall / q << " q, base " << sm.base / q << " q");
    CHECK(sm.wall == approx(q).epsilon(0.01));
    CHECK(sm.wall == approx(sm.base).epsilon(1e-3));
    for (const int by : {2, 4}) {
        const Plateau fl = psc_plateau(Mapping::Smooth, Advect::Flip, by, 2.4e-3);
        MESSAGE((5 * by) << " cells: ADVECT FLIP wall " << fl.wall / q << " q, base " << fl.base / q << " q");
        CHECK(fl.wall == approx(q).epsilon(0.01));
        CHECK(fl.wall == approx(fl.base).epsilon(1e-3));
    }
}

namespace {

// Sand (c = 0, phi = 30 deg, rho = 2000) W m x 4 m against a vertical wall at x = 2 m on
// a rough base, a smooth side at x = 2 + W, cells of L on a (2 + W) m x 6 m lattice,
// damping 0.8. W = 6 m unless given (the active wedge reaches 2.3 m from the wall).
Scene retaining_scene(double L, bool smooth, double W = 6) {
    Scene s;
    const double X = 2 + W;
    s.mx = int(X / L + 0.5); s.my = int(6 / L); s.cell_m = L;
    s.materials.push_back(Material::mohr(1, 2e7, 0.3, 2000, 30, 0));
    s.clusters.push_back({1, {2, 0, X, 4}, 2, {}});
    s.fixes.push_back({kFixX | kFixY, {0, 0, X, 0}, {}});
    s.fixes.push_back({kFixX, {X, L, X, 6}, {}});
    Wall w;
    w.id = 1; w.box = {2, L, 2, 5}; w.smooth = smooth;
    s.walls.push_back(w);
    s.gravity_y = -9.81; s.damping = 0.8; s.steps = 1;
    return s;
}

// The points behind the wall's face (x < 2 m moved with the wall) now.
long points_behind(const Simulation& sim) {
    const Points& p = sim.points();
    const double face = 2 + sim.walls()[0].dx;
    long behind = 0;
    for (std::size_t k = 0; k < p.size(); ++k) behind += p.x[k] < face;
    return behind;
}

// retaining_scene at L = 0.5 m, settled under gravity with the wall held, then the wall
// moved away (to -x) by `cells` cells. Returns the most points found behind the wall's
// face at any sample.
long retaining(bool smooth, double cells, double& mass_error) {
    const double L = 0.5;
    Scene s = retaining_scene(L, smooth);
    s.dt_s = 1.4e-3;
    REQUIRE(validate(s).empty());
    Simulation sim(s);
    for (int n = 0; n < 1000; ++n) sim.step();  // settle
    const double v = 0.05;
    sim.set_wall_velocity(1, -v, 0);
    const long steps = long(cells * L / v / s.dt_s);
    long worst = 0;
    for (long n = 1; n <= steps; ++n) {
        sim.step();
        worst = std::max(worst, points_behind(sim));
    }
    mass_error = sim.mass_inside() + sim.mass_outflow() - sim.mass_initial();
    CHECK(sim.mass_outflow() == 0.0);
    return worst;
}

}  // namespace

TEST_CASE("a wall moved four cells away from sand: no point passes behind it, rough or smooth [slow]") {
    for (bool smooth : {false, true}) {
        double mass_error = 1;
        const long behind = retaining(smooth, 4, mass_error);
        INFO(std::string(smooth ? "smooth wall" : "rough wall"));
        CHECK(behind == 0);
        CHECK(mass_error == 0.0);
    }
}

namespace {

// A wall that meets a free elastic block from a distance (no gravity, no damping): a
// column of nodes two cells (K = 1) from the block, driven towards it at v = 0.5 m/s, meets
// it at t = 1 s. The block leaves a rigid wall moving at v at (1 + e) v, e its restitution:
// 2 v if elastic (its energy in the wall's frame kept), never above, and never less than
// v. The upper bound is also a check that the impact creates no energy. Made that far
// from the material, the wall used to be bonded: it pulled the block it had pushed (up to
// 105 kN/m, as much as it pushed) and carried it along at its own speed (0.99-1.00 v).
// Measured now: 1.80 / 1.70 v (rough / smooth) at 4 cells across the block, 1.83 / 1.99 v
// at 8; the wall's force never below 0. With a second block behind the wall, two cells
// away (material on both sides, neither within a cell), the wall takes the side it is
// driven towards: the same.
struct WallMeeting {
    double v_after = 0;                 // the block's centroid velocity from t = 2 s to 3 s [m/s]
    double min_force = 0, max_force = 0;  // the wall's force on the material, every step [N/m]
};
WallMeeting meet_block(bool smooth, int K, bool behind = false, Advect advect = Advect::Eq12) {
    Scene s;
    s.mx = 24 * K; s.my = 8 * K; s.cell_m = 0.25 / K;
    s.materials.push_back(Material::elastic(1, 1e7, 0.3, 2000));
    s.clusters.push_back({1, {1.5, 0.5, 2.5, 1.5}, 2, {}});
    if (behind) s.clusters.push_back({1, {0, 0.5, 0.5, 1.5}, 2, {}});  // a block behind the wall too, which it leaves
    Wall w;
    w.id = 1; w.box = {1, 0.25, 1, 1.75}; w.vx = 0.5; w.smooth = smooth;
    s.walls.push_back(w);
    s.damping = 0; s.dt_s = 4e-4 / K; s.steps = 1;
    if (advect == Advect::Flip) s.mapping = Mapping::Smooth;
    s.advect = advect;
    REQUIRE(validate(s).empty());
    Simulation sim(s);
    const Points& p = sim.points();
    auto centre_x = [&] {  // the mean x of the block ahead (one material: equal masses)
        double x = 0;
        long n = 0;
        for (std::size_t k = 0; k < p.size(); ++k)
            if (p.x[k] > 1) { x += p.x[k]; ++n; }
        return x / double(n);
    };
    WallMeeting r;
    double x2 = 0;
    const long steps = long(3.0 / s.dt_s + 0.5), at2 = long(2.0 / s.dt_s + 0.5);
    for (long n = 1; n <= steps; ++n) {
        sim.step();
        r.min_force = std::min(r.min_force, sim.walls()[0].fx);
        r.max_force = std::max(r.max_force, sim.walls()[0].fx);
        if (n == at2) x2 = centre_x();
    }
    r.v_after = centre_x() - x2;  // over 1 s
    return r;
}

}  // namespace

TEST_CASE("a wall that meets a free block from a distance pushes it off and never pulls") {
    const double v = 0.5;
    struct Case { int K; bool behind; };
    for (const Case c : {Case{1, false}, Case{2, false}, Case{1, true}})
        for (bool smooth : {false, true}) {
            const WallMeeting r = meet_block(smooth, c.K, c.behind);
            MESSAGE(std::string(smooth ? "smooth" : "rough") << " wall, " << 4 * c.K << " cells across the block"
                    << std::string(c.behind ? ", another behind the wall" : "") << ": it leaves at " << r.v_after / v
                    << " v; the wall's force from " << r.min_force << " to " << r.max_force << " N/m");
            CHECK(r.max_force > 0);        // it pushed ...
            CHECK(r.min_force >= 0);       // ... and never pulled
            CHECK(r.v_after > 1.5 * v);    // the block bounced off (a bonded wall carries it at v)
            CHECK(r.v_after <= 2 * v);     // no faster than an elastic bounce (faster: energy created)
        }
}

// With ADVECT FLIP: the same bounds. The wall's force includes its impact, the change of
// momentum it gives the points of the nodes it takes (flip_transfer).
TEST_CASE("ADVECT FLIP: a wall that meets a free block pushes it off, never pulls, and makes no energy [slow]") {
    const double v = 0.5;
    for (const int K : {1, 2})
        for (bool smooth : {false, true}) {
            const WallMeeting r = meet_block(smooth, K, false, Advect::Flip);
            MESSAGE("ADVECT FLIP, " << std::string(smooth ? "smooth" : "rough") << " wall, " << 4 * K << " cells across the block: it leaves at "
                    << r.v_after / v << " v; the wall's force from " << r.min_force << " to " << r.max_force << " N/m");
            CHECK(r.max_force > 0);
            CHECK(r.min_force >= 0);
            CHECK(r.v_after > 1.5 * v);
            CHECK(r.v_after <= 2 * v);
        }
}

TEST_CASE("a SMOOTH wall drives its line of nodes across the line only") {
    Scene s;
    s.mx = 10; s.my = 24; s.cell_m = 0.1;
    s.materials.push_back(Material::elastic(1, 1e7, 0.3, 1000));
    s.clusters.push_back({1, {0, 0, 1, 2}, 2, {}});
    s.fixes.push_back({kFixX | kFixY, {0, 0, 1, 0}, {}});
    Wall w;
    w.id = 1; w.box = {0, 2, 1, 2}; w.vx = 0.02; w.vy = -0.005; w.smooth = true;
    s.walls.push_back(w);
    s.damping = 0.8; s.dt_s = 4e-4; s.steps = 1;
    REQUIRE(validate(s).empty());
    Simulation sim(s);
    for (int n = 0; n < 50; ++n) sim.step();
    CHECK(sim.walls()[0].dx == 0.0);  // no travel along the line
    CHECK(sim.walls()[0].dy == approx(-0.005 * 50 * 4e-4).epsilon(1e-12));
    CHECK(sim.du_y()[std::size_t(sim.node(5, 20))] == approx(-0.005 * 4e-4).epsilon(1e-12));
    CHECK(sim.walls()[0].fx == 0.0);  // x is free: the wall exerts no force along itself
    // A box of nodes (not a line) cannot be smooth.
    s.walls[0].box = {0, 1.9, 1, 2};
    const Diagnostics d = validate(s);
    REQUIRE(d.size() == 1);
    CHECK(d[0].message.find("SMOOTH wall is one line of nodes") != std::string::npos);
}

TEST_CASE("the reaction of each FIX card, and their sum rx ry") {
    Scene s;
    REQUIRE(read_deck("decks/verify_column_stiff.deck", s).empty());
    s.fixes.insert(s.fixes.begin() + 1, Fix{kFixY, {0, 0, 0.25, 0}, {}});  // a part of the base, listed before the rest
    Simulation sim(s);
    for (int n = 0; n < 200; ++n) sim.step();
    double sx = 0, sy = 0;
    for (std::size_t f = 0; f < s.fixes.size(); ++f) { sx += sim.fix_reaction_x(f); sy += sim.fix_reaction_y(f); }
    // rx sums side reactions of either sign, a few times |ry| in all, that cancel: the same ~60
    // nodal reactions summed in another order differ by about 60 x 1.1e-16 of that at most.
    CHECK(std::fabs(sx - sim.reaction_x()) < 1e-12 * std::fabs(sim.reaction_y()));
    CHECK(sy == approx(sim.reaction_y()).epsilon(1e-12));
    CHECK(sim.fix_reaction_y(1) != 0.0);  // the first card holding a node in y takes its reaction
}

namespace {

// Run-outs to the left and right of a granular column (c = 0, phi = 30 deg, a = 2) standing
// in the middle of a lattice, after it collapsed.
void runouts(Mapping mapping, Motion motion, double& left, double& right, Advect advect = Advect::Eq12) {
    Scene s;
    s.mx = 64; s.my = 20; s.cell_m = 0.25;
    s.materials.push_back(Material::mohr(1, 1e7, 0.3, 2000, 30, 0));
    s.clusters.push_back({1, {7, 0, 9, 4}, 2, {}});
    s.fixes.push_back({kFixX | kFixY, {0, 0, 16, 0}, {}});
    s.gravity_y = -9.81; s.damping = 0.1; s.dt_s = 5e-4; s.steps = 1;
    s.mapping = mapping; s.motion = motion; s.advect = advect;
    Simulation sim(s);
    for (int n = 0; n < 3000; ++n) sim.step();
    const Points& p = sim.points();
    left = 8 - *std::min_element(p.x.begin(), p.x.end());
    right = *std::max_element(p.x.begin(), p.x.end()) - 8;
}

}  // namespace

TEST_CASE("a symmetric column collapses symmetrically with MOTION CENTRE, and with MAPPING SMOOTH and MOTION BILINEAR [slow]") {
    for (const auto& choice : {std::pair{Mapping::Paper, Motion::Centre}, std::pair{Mapping::Smooth, Motion::Bilinear}}) {
        // Plain variables, not a structured binding: INFO captures them in a lambda, which
        // C++17 does not allow for bindings (Clang refuses it).
        const Mapping mapping = choice.first;
        const Motion motion = choice.second;
        double left = 0, right = 0;
        runouts(mapping, motion, left, right);
        INFO("mapping " << int(mapping) << ", motion " << int(motion) << ": left " << left << " m, right " << right << " m");
        CHECK(left > 3);  // it did collapse (the column is 1 m either side)
        CHECK(right == approx(left).epsilon(0.01));
    }
}

TEST_CASE("a symmetric column collapses symmetrically with ADVECT FLIP [slow]") {
    double left = 0, right = 0;
    runouts(Mapping::Smooth, Motion::Bilinear, left, right, Advect::Flip);
    MESSAGE("ADVECT FLIP: left " << left << " m, right " << right << " m");
    CHECK(left > 3);
    CHECK(right == approx(left).epsilon(0.01));
}

namespace {

// retaining_scene's sand (W wide, H = 4 m high) at L (0.25 m unless given) with MAPPING
// SMOOTH; settled under gravity with the wall held, then the wall moved away from it by 4
// cells: at v (5 mm/s unless given) over its first 0.25 m, where the force is read, then
// at 5 cm/s. The force the wall takes, averaged over 0.05 to 0.25 m of travel (1.25 % to
// 6 % of H: the active state, reached at a few tenths of a percent), and the most points
// ever found behind its face.
struct Retained {
    double force = 0, mass_error = 1, outflow = 1;
    long behind = -1;
};
Retained retained(bool smooth_wall, double L = 0.25, Advect advect = Advect::Eq12, double v = 0.005, double W = 6) {
    Scene s = retaining_scene(L, smooth_wall, W);
    s.mapping = Mapping::Smooth; s.advect = advect;
    s.dt_s = 0.8 * stable_dt(s);  // (0.5 read the same thrusts to 3e-4 of them, in 1.6 times the steps)
    REQUIRE(validate(s).empty());
    Simulation sim(s);
    for (long n = 0; n < long(2.0 / s.dt_s); ++n) sim.step();  // settle
    Retained r;
    double sum = 0;
    long count = 0, behind = 0;
    for (const double u : {v, 0.05}) {
        const bool slow = u == v;
        sim.set_wall_velocity(1, -u, 0);
        const double to = slow ? 0.25 : 4 * L;
        while (-sim.walls()[0].dx < to - 1e-9) {
            sim.step();
            const double travel = -sim.walls()[0].dx;
            if (slow && travel > 0.05) { sum += sim.walls()[0].fx; ++count; }
            behind = std::max(behind, points_behind(sim));
        }
    }
    r.force = sum / double(count);
    r.behind = behind;
    r.mass_error = sim.mass_inside() + sim.mass_outflow() - sim.mass_initial();
    r.outflow = sim.mass_outflow();
    return r;
}

// retained()'s thrust against Rankine's (a smooth wall) and Coulomb's (a rough one, the
// horizontal part) within tol, no point ever behind the face, the mass exact and inside.
// Rankine: K_a = (1 - sin phi) / (1 + sin phi) = 1/3, gamma H^2 / 6 = 52.3 kN/m. Coulomb
// with delta = phi = 30 deg (a bonded wall: the sand beside it shears at its own
// friction): K_a cos(delta) = cos^2 phi / (1 + sqrt(sin(phi + delta) sin phi / cos delta))^2
// = 0.2574, 40.4 kN/m.
void check_thrust(const char* what, double L, Advect advect, double v, double W, double tol) {
    const double gamma = 2000 * 9.81, H = 4, phi = 30 * kDeg;
    const double rankine = gamma * H * H / 6;
    const double coulomb = 0.5 * gamma * H * H * std::pow(std::cos(phi), 2) / std::pow(1 + std::sqrt(std::sin(2 * phi) * std::sin(phi) / std::cos(phi)), 2);
    for (const bool smooth : {true, false}) {
        const Retained r = retained(smooth, L, advect, v, W);
        const double ref = smooth ? rankine : coulomb;
        MESSAGE(std::string(what) << ", " << std::string(smooth ? "smooth wall: " : "rough wall: ") << r.force << " N/m, " << r.force / ref << " of "
                     << std::string(smooth ? "Rankine's" : "Coulomb's") << " thrust; points behind it at most " << r.behind);
        CHECK(r.force == approx(ref).epsilon(tol));
        CHECK(r.behind == 0);
        CHECK(r.mass_error == 0.0);
        CHECK(r.outflow == 0.0);
    }
}

}  // namespace

// A wall that drags the sand (walls bonded both ways) read 0.14-0.67 of Rankine. On 4 m
// of sand (the active wedge reaches 2.3 m): 0.9043 of Rankine and 0.9336 of Coulomb,
// where 6 m read 0.9068 and 0.9383 (before follow_material), in two thirds of the time.
TEST_CASE("a retaining wall moved away from sand: Rankine's thrust on a smooth wall, Coulomb's on a rough one; no point passes it in 4 cells [slow]") {
    check_thrust("eq. 12, L = 0.25 m", 0.25, Advect::Eq12, 0.005, 4, 0.10);
}

// The same with ADVECT FLIP, at L = 0.125 m (32 cells over H) on 4 m of sand (the active
// wedge reaches 2.3 m; 6 m gave the same thrust to 1e-4), the wall at 2 cm/s while the
// force is read. At L = 0.25 m FLIP's smooth wall reads 0.886 of Rankine (eq. 12's 0.904):
// both dip to 0.83-0.85 while the wall's face crosses the first half of its cell and
// recover to 0.94 by the end of it, a discretisation error the two transfers share that
// falls with L. Measured: 0.947 of Rankine, 0.934 of Coulomb. About 3 minutes: make
// verify runs it; make test runs the case below at L = 0.25 m.
TEST_CASE("ADVECT FLIP: a retaining wall moved away from sand, Rankine's and Coulomb's thrust at 32 cells over H; no point passes it [slow][verify]") {
    check_thrust("ADVECT FLIP, L = 0.125 m", 0.125, Advect::Flip, 0.02, 4, 0.10);
}

// The same at L = 0.25 m (16 cells over H), the wall at 2 cm/s while the force is read:
// the discretisation error of the wall's face crossing its first cell (above) is larger
// here, measured 0.870 of Rankine and 0.888 of Coulomb (0.947 and 0.934 at L = 0.125 m,
// the case above): within 15 %, no point behind the face, mass exact. Half a minute.
TEST_CASE("ADVECT FLIP: a retaining wall moved away from sand at 16 cells over H: Rankine's and Coulomb's thrust within the coarse lattice's error; no point passes it [slow]") {
    check_thrust("ADVECT FLIP, L = 0.25 m", 0.25, Advect::Flip, 0.02, 4, 0.15);
}
