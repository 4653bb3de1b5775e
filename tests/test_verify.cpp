// The coarse rung of every verification case of `make verify` (tools/verify.sh), each
// against its reference (closed form), with the tolerance the coarsest lattice
// allows and the reason for it. The full ladder (--refine 1, 2, 4; 1x1, 2x2, 4x4
// points per cell) is `make verify`; the numbers it measured are in tests/README.md
// (the verification ladder). One ladder runs here: the footing's, to 32 cells over its
// width with one point per cell, where it is within 3 % of 2 + pi.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include "../lpfdm.hpp"
#include "common.hpp"

using namespace lpfdm;

namespace {

Scene load(const char* deck) {
    Scene s;
    const Diagnostics d = read_deck(deck, s);
    for (const auto& e : d) MESSAGE(e.str());
    REQUIRE(d.empty());
    return s;
}

void set(Scene& s, const char* key, double v) { REQUIRE(apply_setting(s, key, v).empty()); }

// Constrained modulus of an elastic material.
double constrained(const Material& m) { return m.E * (1 - m.nu) / ((1 + m.nu) * (1 - 2 * m.nu)); }

// Settlement of a point that started at height Y in the confined column: the stress is
// updated from strain increments of the current configuration, so sigma_yy = M ln(stretch),
// while in the material's own coordinate Y the stress is exactly -rho g (H - Y) (the weight
// above a point does not change). Integrating the stretch exp(-rho g (H - Y) / M) over Y:
double column_settlement(double Y, double H, double rho, double g, double M) {
    const double a = rho * g / M;
    return Y - std::exp(-a * H) * (std::exp(a * Y) - 1) / a;
}

// Mean settlement of the points that started in the top row of the column.
struct TopRow {
    std::vector<double> y0;  // initial height by point id
    double ytop = 0;
    explicit TopRow(const Simulation& sim) {
        const Points& p = sim.points();
        y0.assign(p.size(), 0);
        for (std::size_t k = 0; k < p.size(); ++k) {
            y0[std::size_t(p.id[k])] = p.y[k];
            ytop = std::max(ytop, p.y[k]);
        }
    }
    double settlement(const Simulation& sim) const {
        const Points& p = sim.points();
        double s = 0;
        int n = 0;
        for (std::size_t k = 0; k < p.size(); ++k)
            if (y0[std::size_t(p.id[k])] > ytop - 1e-9) { s += ytop - p.y[k]; ++n; }
        return s / n;
    }
};

struct ColumnResult {
    double syy_l2 = 0;         // relative L2 error of sigma_yy over the points
    double representation = 0; // the part of it that one stress per cell must make: rho g L/4 at every point
    double settlement_err = 0; // top row, against column_settlement()
    double strain = 0;         // largest strain, rho g H / M
};

ColumnResult column_at_rest(const char* deck, const Cycle& cycle = kCycles[0]) {
    Scene s = load(deck);
    cycle.apply(s);
    const double H = 12, rho = s.materials[0].rho, g = -s.gravity_y, M = constrained(s.materials[0]);
    Simulation sim(s);
    const TopRow top(sim);
    for (long n = 0; n < s.steps; ++n) sim.step();
    MESSAGE(std::string(cycle.name) << ": kinetic energy at the end " << sim.kinetic_energy() << " J/m, strain energy " << sim.energy().strain << " J/m");
    // At rest: what still moves would swing the stress by about sqrt(kinetic / strain
    // energy) of itself, below 1e-6 (measured: 3e-16, 2e-12 and 4e-10 J/m of 9 100-9 300).
    REQUIRE(sim.kinetic_energy() < 1e-12 * sim.energy().strain);
    const Points& p = sim.points();
    double e2 = 0, r2 = 0, u = 0, uref = 0;
    int ntop = 0;
    for (std::size_t k = 0; k < p.size(); ++k) {
        const double Y = top.y0[std::size_t(p.id[k])], ref = -rho * g * (H - Y);
        e2 += (p.syy[k] - ref) * (p.syy[k] - ref);
        r2 += ref * ref;
        if (Y > top.ytop - 1e-9) { u += Y - p.y[k]; uref += column_settlement(Y, H, rho, g, M); ++ntop; }
    }
    ColumnResult c;
    c.syy_l2 = std::sqrt(e2 / r2);
    c.representation = rho * g * s.cell_m / 4 / std::sqrt(r2 / double(p.size()));
    c.settlement_err = u / uref - 1;
    c.strain = rho * g * H / M;
    return c;
}

struct Ring {
    double period = 0, peak = 0, reference_period = 0, strain = 0;
};

// The ringing column: top settlement every step; period from the crossings of the middle
// level (inflection points, where linear interpolation is best), peak over the static
// settlement of the same points.
Ring ringing(const char* deck) {
    const Scene s = load(deck);
    const double H = 12, rho = s.materials[0].rho, g = -s.gravity_y, M = constrained(s.materials[0]);
    Simulation sim(s);
    const TopRow top(sim);
    std::vector<double> t{0}, u{0};
    for (long n = 0; n < s.steps; ++n) {
        sim.step();
        t.push_back(sim.time());
        u.push_back(top.settlement(sim));
    }
    const double us = column_settlement(top.ytop, H, rho, g, M);
    const double mid = 0.5 * (*std::min_element(u.begin(), u.end()) + *std::max_element(u.begin(), u.end()));
    std::vector<double> cross;
    for (std::size_t k = 1; k < u.size(); ++k)
        if ((u[k - 1] - mid) * (u[k] - mid) < 0) cross.push_back(t[k - 1] + (mid - u[k - 1]) * (t[k] - t[k - 1]) / (u[k] - u[k - 1]));
    REQUIRE(cross.size() >= 3);
    if (cross.size() % 2 == 0) cross.pop_back();  // first and last in the same direction
    Ring r;
    r.period = 2 * (cross.back() - cross.front()) / double(cross.size() - 1);
    std::size_t k = 1;
    while (k + 1 < u.size() && !(u[k] >= u[k - 1] && u[k] >= u[k + 1] && u[k] > us)) ++k;
    r.peak = u[k] / us;
    r.reference_period = 4 * H / std::sqrt(M / rho);
    r.strain = rho * g * H / M;
    return r;
}

// -q / W of wall 1 against its travel, each step.
struct WallCurve {
    std::vector<double> travel, q;
};

WallCurve wall_curve(const Scene& s, double width) {
    Simulation sim(s);
    WallCurve c;
    for (long n = 0; n < s.steps; ++n) {
        sim.step();
        REQUIRE(sim.healthy());
        c.travel.push_back(-sim.walls()[0].dy);
        c.q.push_back(-sim.walls()[0].fy / width);
    }
    return c;
}

// The footing of verify_footing.deck: q / c at 1.4 cm of settlement (c = 20 kPa, B = 1 m),
// the reading make verify takes.
double footing_q_over_c(const Scene& s) {
    const WallCurve c = wall_curve(s, 1.0);
    std::size_t k = 0;
    while (k < c.travel.size() && c.travel[k] < 0.014) ++k;
    REQUIRE(k < c.travel.size());
    return c.q[k] / 20000;
}

// Does the cut stand? Under local damping a cut at rest has its unbalanced-force ratio
// fall by orders of magnitude each second; a collapsing (or creeping) one keeps it high.
bool cut_stands(double g) {
    Scene s = load("decks/verify_cut.deck");
    s.outputs.clear();
    s.gravity_y = -g;
    Simulation sim(s);
    double u_two_thirds = 0;
    for (long n = 1; n <= s.steps; ++n) {
        sim.step();
        REQUIRE(sim.healthy());
        if (n == 2 * s.steps / 3) u_two_thirds = sim.unbalanced_ratio();
    }
    const double u = sim.unbalanced_ratio();
    MESSAGE("cut at g = " << g << ": unbalanced ratio " << u_two_thirds << " at 2 s, " << u << " at 3 s");
    return u < 1e-7 || u < 0.1 * u_two_thirds;
}

}  // namespace

TEST_CASE("verify: stiff confined column at rest: the sigma_yy error is one stress per cell, the settlement exact") {
    const ColumnResult c = column_at_rest("decks/verify_column_stiff.deck");
    MESSAGE("sigma_yy L2 error " << c.syy_l2 << " (one stress per cell: " << c.representation << "), top settlement error " << c.settlement_err);
    // Every point takes its cell's stress, the exact value at the cell centre; the points of
    // 2x2 per cell sit L/4 above or below it, so each is off by rho g L/4. Strain 1e-4.
    CHECK(c.syy_l2 == approx(c.representation).epsilon(0.02));
    // The nodes of the lumped-mass lattice settle as the exact column does; a point between
    // two nodes moves with the straight line between them, off the parabola by up to
    // (3/32) L^2 u'' at a quarter cell: 3 L^2 / (16 H^2) of the top settlement (3.3e-4
    // here), plus the strain level.
    const double L = 0.5, H = 12;
    CHECK(std::fabs(c.settlement_err) < 3 * L * L / (16 * H * H) + c.strain);
}

TEST_CASE("verify: confined column at 1 % strain: stress and settlement high by about the strain [slow]") {
    const ColumnResult c = column_at_rest("decks/column.deck");
    MESSAGE("sigma_yy L2 error " << c.syy_l2 << ", top settlement error " << c.settlement_err << ", base strain " << c.strain);
    // Eq. 8 divides the points' sum of V sigma by the cell area L^2; compressed points fill
    // less than L^2 of a cell they do not leave, so the point stress that balances the
    // weight is higher by up to the volumetric strain (rho g H / M = 0.98 % at the base),
    // and the column is softer by as much. This does not vanish with refinement (see
    // tests/README.md): only with the strain.
    CHECK(c.syy_l2 < c.representation + c.strain);
    CHECK(c.settlement_err > 0);
    CHECK(c.settlement_err < 1.5 * c.strain);
}

// #58's target for the column, in each cycle: sigma_yy within 2 % (L2) at 24 cells over H,
// the coarsest rung. One stress per cell leaves rho g L/4 at every point (1.0 % in L2)
// and the 1 % strain as much again (the case above). Measured 1.96 % (the paper's
// mapping), 1.55 % (SMOOTH), 1.70 % (FLIP).
TEST_CASE("verify: confined column at 1 % strain, 24 cells over H: sigma_yy within 2 % in each cycle [slow]") {
    for (const Cycle& cycle : kCycles) {
        const ColumnResult c = column_at_rest("decks/column.deck", cycle);
        MESSAGE(std::string(cycle.name) << ": sigma_yy L2 error " << c.syy_l2 << ", top settlement error " << c.settlement_err);
        CHECK(c.syy_l2 < 0.02);
    }
}

TEST_CASE("verify: stiff ringing column: period 4H/c_p and peak twice the static settlement") {
    const Ring r = ringing("decks/verify_ringing_stiff.deck");
    MESSAGE("period " << r.period << " s (4H/c_p " << r.reference_period << "), peak " << r.peak << " x static");
    // 24 cells over H: the lattice's dispersion of the fundamental mode is below 1e-3
    // (first order in L, 6e-4 measured), the strain (2e-4) does not matter.
    CHECK(r.period == approx(r.reference_period).epsilon(1e-3));
    CHECK(r.peak == approx(2).epsilon(1e-3));
}

TEST_CASE("verify: ringing column at 1 % strain: period and peak off by about the strain [slow]") {
    const Ring r = ringing("decks/verify_ringing.deck");
    MESSAGE("period " << r.period << " s (4H/c_p " << r.reference_period << "), peak " << r.peak << " x static, strain " << r.strain);
    // As at rest, the column is softer by up to its strain (dynamic peak strain 2 rho g H / M).
    CHECK(r.period == approx(r.reference_period).epsilon(r.strain));
    CHECK(r.peak == approx(2).epsilon(2 * r.strain));
}

TEST_CASE("verify: plane-strain compression reaches 2 c tan(45 + phi/2) on its plateau [slow]") {
    Scene s = load("decks/verify_psc.deck");
    s.outputs.clear();
    const WallCurve c = wall_curve(s, 0.1);
    double sum = 0;
    int n = 0;
    for (std::size_t k = 0; k < c.q.size(); ++k)
        if (c.travel[k] >= 0.00015) { sum += c.q[k]; ++n; }
    const double plateau = sum / n, expect = 2 * 9800 * std::tan((45 + 28.648 / 2) * kDeg);
    MESSAGE("plateau q " << plateau << " Pa, Mohr-Coulomb " << expect << " Pa");
    // Five cells across the specimen: the plateau fluctuates by about 1 % as yielding moves
    // between cells, and the wall's speed adds up to its impact stress, 2 % of q.
    CHECK(plateau == approx(expect).epsilon(0.03));
}

TEST_CASE("verify: a vertical cut stands at the limit-analysis critical height and falls above it [slow]") {
    const double ref = 3.83 * std::tan((45 + 28.648 / 2) * kDeg);  // gamma H_c / c
    const double g_ref = ref * 9800 / (1700 * 4);
    // 8 cells over H: the slip surface is drawn through whole cells, which makes the coarse
    // lattice stronger (the ladder converges from above: at 8 cells the bisection finds
    // gamma H_c / c 6 % above the reference, at 16 cells 2 %): the cut must stand at the
    // reference and fall 15 % above it.
    CHECK(cut_stands(g_ref));
    CHECK_FALSE(cut_stands(1.15 * g_ref));
}

TEST_CASE("verify: rough strip footing on weightless Tresca soil: q/c a little above 2 + pi [slow]") {
    Scene s = load("decks/verify_footing.deck");
    s.outputs.clear();
    const double q = footing_q_over_c(s);
    MESSAGE("q/c at 1.4 cm of settlement: " << q << " (Prandtl 2 + pi = " << 2 + kPi << ")");
    // 4 cells over B: the edge nodes of the footing also gather force from the soil cells
    // beside it, so the footing bears as if wider by a fraction of a cell: a first-order
    // error from above, about 0.4 L / B = 10 % here (the ladder halves it per rung).
    CHECK(q > 2 + kPi);
    CHECK(q < 1.15 * (2 + kPi));
}

namespace {

// The footing's ladder with one point per cell, at --refine 1, 2, ... up to `finest`: one
// point per cell, so that no point under the footing crosses a cell edge before the
// reading at 1.4 cm of settlement (L / 2 = 1.56 cm at 32 cells): the error is then the
// first-order one of the footing's edge nodes (about 0.4 L / B from above), halving per
// rung. (With 2 x 2 points the points under the footing cross into the next row of cells
// at L / 4 of settlement, 0.78 cm at 32 cells, and q jumps: tests/README.md.) Returns the
// finest rung's error.
double footing_ladder(int finest) {
    double prev = 0, err = 0;
    for (int r = 1; r <= finest; r *= 2) {
        Scene s = load("decks/verify_footing.deck");
        s.outputs.clear();
        set(s, "CLUSTER1.PPC", 1);
        set(s, "CLUSTER2.PPC", 1);
        lpfdm::refine(s, r);
        const double q = footing_q_over_c(s);
        err = q / (2 + kPi) - 1;
        MESSAGE((4 * r) << " cells over B: q/c " << q << ", " << 100 * err << " % above 2 + pi");
        CHECK(err > 0);  // from above: the footing bears as if wider by a fraction of a cell
        if (r > 1) {  // first order: the error halves per rung (observed order 0.7 to 1.3)
            CHECK(prev / err > 1.6);
            CHECK(prev / err < 2.5);
        }
        prev = err;
    }
    return err;
}

}  // namespace

TEST_CASE("verify: the rough strip footing converges to 2 + pi at first order, 4 to 16 cells over B [slow]") {
    footing_ladder(4);
}

// The rung of 32 cells costs eight times the three before it (about 30 s): make verify.
TEST_CASE("verify: the rough strip footing converges to 2 + pi at first order: within 3 % at 32 cells over B [slow][verify]") {
    CHECK(footing_ladder(8) < 0.03);  // 32 cells over B (--refine 8): within 3 %
}

TEST_CASE("verify: granular column collapse: run-out grows with a, between the published laws for a <= 1 [slow]") {
    const double as[] = {0.5, 1, 2, 4};
    double prev = -1;
    for (double a : as) {
        Scene s = load("decks/verify_collapse.deck");
        s.outputs.clear();
        set(s, "CLUSTER1.Y1", a);
        Simulation sim(s);
        // Front: 99 % of the points behind it (a few points thrown ahead do not count).
        auto front = [&sim]() {
            std::vector<double> x(sim.points().x);
            std::sort(x.begin(), x.end());
            return x[std::size_t(0.99 * double(x.size())) - 1];
        };
        double front_before = 0;
        for (long n = 1; n <= s.steps; ++n) {
            sim.step();
            REQUIRE(sim.healthy());
            if (n == 3 * s.steps / 4) front_before = front();
        }
        CHECK(sim.mass_inside() + sim.mass_outflow() == sim.mass_initial());
        const double runout = front() - 1;
        // The deposit has stopped: its front (known to about a cell: a few points decide the
        // 99th percentile) moved less than two cells in the last second.
        CHECK(std::fabs(runout + 1 - front_before) < 2 * s.cell_m);
        const double lube = a < 2.3 ? 1.2 * a : 1.9 * std::pow(a, 2.0 / 3), lajeunesse = 1.8 * a;
        MESSAGE("a = " << a << ": run-out " << runout << " (Lube 2005 " << lube << ", Lajeunesse 2005 " << lajeunesse
                       << "), mass through the floor " << sim.mass_outflow() / sim.mass_initial());
        CHECK(runout > prev);
        prev = runout;
        // The front is known to two cells (0.25 L0 at 8 cells over L0).
        if (a <= 1) {
            CHECK(runout > lube - 0.25);
            CHECK(runout < lajeunesse + 0.25);
        }
        // Taller columns: a Mohr-Coulomb continuum with a constant friction angle runs out
        // further than the experiments (also seen with MPM); at least as far as Lube's law.
        if (a >= 2) CHECK(runout > lube);
        CHECK(sim.mass_outflow() == 0);  // nothing leaves through the rough floor
        // The deposit at rest, its nodes too: kinetic energy at most 1 % of gravity's work
        // (5e-6, 2e-6, 1e-3 and 2e-4 of it at a = 0.5, 1, 2, 4). A move held at the floor
        // that took the lattice's field across the floor's length too kept a lone point from
        // following its cell: the node above it fell on for the whole run (0.15 of it at a = 0.5).
        CHECK(sim.energy().kinetic < 0.01 * sim.energy().w_gravity);
    }
}

namespace {

// verify_hopper.deck with a slot of D m in the middle of its floor (its two FIX cards),
// refined r times, in the given cycle: the steady discharge rate (kg/s per m), the slope of
// the outflow against time over the run's second half (t >= 1 s, every 20 steps).
double discharge_rate(double D, int r = 1, Mapping mapping = Mapping::Paper, Advect advect = Advect::Eq12) {
    Scene s = load("decks/verify_hopper.deck");
    s.outputs.clear();
    set(s, "FIX1.X1", 3 - D / 2);
    set(s, "FIX2.X0", 3 + D / 2);
    s.mapping = mapping;
    s.advect = advect;
    lpfdm::refine(s, r);
    Simulation sim(s);
    double st = 0, sm = 0, stt = 0, stm = 0;
    int n = 0;
    for (long k = 0; k < s.steps; ++k) {
        sim.step();
        REQUIRE(sim.healthy());
        if (sim.time() >= 1.0 - 1e-9 && (k + 1) % (20 * r) == 0) {
            const double t = sim.time(), m = sim.mass_outflow();
            st += t; sm += m; stt += t * t; stm += t * m; ++n;
        }
    }
    return (n * stm - st * sm) / (n * stt - st * st);
}

}  // namespace

TEST_CASE("verify: discharge through a slot grows as D^(3/2) (Beverloo), with a one-cell offset [slow]") {
    std::vector<double> logd, logq;
    const double L = load("decks/verify_hopper.deck").cell_m;
    for (int cells : {2, 4, 8}) {
        const double D = cells * L, rate = discharge_rate(D);
        MESSAGE("slot of " << cells << " cells (" << D << " m): " << rate << " kg/s per m, Beverloo C = " << rate / (2000 * std::sqrt(9.81) * std::pow(D, 1.5)));
        logd.push_back(std::log(D));
        logq.push_back(std::log(rate));
    }
    const double p = (logq.back() - logq.front()) / (logd.back() - logd.front());
    MESSAGE("exponent over 2 to 8 cells: " << p << " (Beverloo 3/2)");
    // Beverloo's (D - k d)^(3/2) with the cell in the role of the grain: an offset of k cells
    // steepens the exponent between D = 2 and 8 cells to 1.5 ln((8 - k) / (2 - k)) / ln 4,
    // 1.5 for k = 0 and 2.0 for k = 0.85 (the coarse rung's 1.70 gives k = 0.43).
    CHECK(p > 1.5);
    CHECK(p < 2.0);
}

// MAPPING SMOOTH and ADVECT FLIP pass less through a narrow slot than the paper's
// cycle: they lose a band at each edge of the slot that grows with the points' squares
// (Beverloo's offset k: 1.2-1.4 cells with FLIP, 0.4-0.8 with SMOOTH, 0-0.5 with the
// paper's cycle; tests/README.md: under FLIP the material above the slot hardly moves,
// and the points in it move at about half their own increments). A band of so many
// cells falls with the cell, so at a slot of fixed width the deficit halves with each
// halving of the cell: at D = 0.25 m and 2, 4, 8 cells across it the paper's cycle
// passes 921 / 877 / 923 kg/s per m, SMOOTH 580 / 817 / 899, FLIP 226 / 540 / 730. The
// paper's cycle is the reference (its rate within 5 % of their mean at every rung);
// each cycle's deficit against the mean of the paper's falls at first order (by 1.85
// and 2.07 with FLIP), SMOOTH's faster.
// About five minutes (FLIP's finest rung, 73 728 points, 16 000 steps): make verify.
TEST_CASE("verify: a narrow slot's discharge under MAPPING SMOOTH and ADVECT FLIP converges to the paper's cycle's as the cell halves [slow][verify]") {
    const double D = 0.25;  // two cells of the deck's lattice
    std::vector<double> paper, smooth, flip;
    for (int r : {1, 2, 4}) {
        paper.push_back(discharge_rate(D, r));
        smooth.push_back(discharge_rate(D, r, Mapping::Smooth));
        flip.push_back(discharge_rate(D, r, Mapping::Smooth, Advect::Flip));
        MESSAGE((2 * r) << " cells across the slot: the paper's cycle " << paper.back() << ", MAPPING SMOOTH " << smooth.back() << ", with ADVECT FLIP "
                        << flip.back() << " kg/s per m");
    }
    const double ref = (paper[0] + paper[1] + paper[2]) / 3;
    for (const double q : paper) CHECK(std::fabs(q / ref - 1) < 0.05);  // the paper's cycle: no band at the slot's edges to resolve
    for (std::size_t i = 1; i < 3; ++i) {
        CHECK(smooth[i] > smooth[i - 1]);
        CHECK(flip[i] > flip[i - 1]);
        // First order: the deficit halves per rung (the paper's own scatter, 5 %, moves the
        // finest deficit's ratio by up to 0.3).
        CHECK((ref - flip[i - 1]) / (ref - flip[i]) > 1.6);
    }
    CHECK(ref - smooth[1] < 0.5 * (ref - smooth[0]));
    CHECK(std::fabs(smooth[2] / ref - 1) < 0.05);  // 8 cells across the slot: within the paper's scatter
    CHECK(flip[2] / ref > 0.75);
}

// #62's invariant on every shipped deck, over its whole run: no cell's points hold more
// than twice its area (packing() at most 2 after every step; the flows that would pack
// more say SHIFT), and no point's move was clamped on a face or a fixed edge (parked()).
// A few minutes of runs (psc.deck alone 136 000 steps): make verify only.
TEST_CASE("verify: every shipped deck, its whole run: no cell over twice its area, no point parked [slow][verify]") {
    std::vector<std::filesystem::path> decks;
    for (const auto& e : std::filesystem::directory_iterator("decks"))
        if (e.path().extension() == ".deck") decks.push_back(e.path());
    std::sort(decks.begin(), decks.end());
    REQUIRE(decks.size() > 30);
    for (const auto& deck : decks) {
        Scene s;
        REQUIRE_MESSAGE(read_deck(deck.string(), s).empty(), deck.string());
        s.outputs.clear();
        Simulation sim(s);
        double most = 0;
        for (long k = 0; k < s.steps; ++k) {
            sim.step();
            most = std::max(most, sim.packing());
        }
        MESSAGE(deck.string() << ": " << s.steps << " steps, packing at most " << most << ", parked " << sim.parked() << ", shifted " << sim.shifted());
        CHECK_MESSAGE(sim.healthy(), deck.string());
        CHECK_MESSAGE(most <= 2.0, deck.string());
        CHECK_MESSAGE(sim.parked() == 0, deck.string());
    }
}
