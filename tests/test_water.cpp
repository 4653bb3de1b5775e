// Pore water (WATER, DRAIN, LOAD: the header's section "Pore water and loads"): effective
// stress, the undrained response, Darcy flow, each against its closed form; the water's
// volume kept by the flow; the deck's checks.
#include <doctest/doctest.h>

#include <cmath>
#include <map>
#include <string>
#include <vector>

#include "../lpfdm.hpp"
#include "common.hpp"

using namespace lpfdm;

namespace {

Scene water_scene(const std::string& text) {
    Scene s;
    Unread u;
    const Diagnostics d = parse_deck_text(text, "water.deck", s, &u);
    REQUIRE(d.empty());
    const Diagnostics v = validate(s, u);
    for (const auto& m : v) INFO(m.str());
    REQUIRE(v.empty());
    return s;
}

// Errors a deck draws (parse and validate), as one text.
std::string water_errors(const std::string& text) {
    Scene s;
    Unread u;
    Diagnostics d = parse_deck_text(text, "water.deck", s, &u);
    for (const auto& m : validate(s, u)) d.push_back(m);
    std::string all;
    for (const auto& m : d) all += m.str() + "\n";
    return all;
}

// Terzaghi's series for the excess pore pressure at depth z below the drained top.
double terzaghi(double p0, double z, double H, double T) {
    double p = 0;
    for (int i = 0; i < 400; ++i) {
        const double m = kPi * (2 * i + 1) / 2;
        p += 2 * p0 / m * std::sin(m * z / H) * std::exp(-m * m * T);
    }
    return p;
}

double constrained_modulus(double E, double nu) { return E * (1 - nu) / ((1 + nu) * (1 - 2 * nu)); }

const char* kOedometer = R"(GRID 2 8 0.25
MATERIAL 1 ELASTIC E=10E6 NU=0.3 RHO=2000 POROSITY=0.4
WATER KW=2E7 UNDRAINED
CLUSTER 1 0 0 0.5 2
FIX XY 0 0 0.5 0
FIX X 0 0 0 2
FIX X 0.5 0 0.5 2
LOAD 0 2 0.5 2 TY=-10000
DAMPING 0.8
STEP 1E-4 20000
)";

}  // namespace

TEST_CASE("undrained oedometric loading: the pore pressure takes q (KW/n) / (KW/n + M)") {
    // KW = 2E7 (a compressible fluid) so that the split is far from all-to-the-water:
    // KW/n = 5E7 Pa, M = 13.46 MPa, p = 0.788 q.
    const Scene s = water_scene(kOedometer);
    Simulation sim(s);
    for (long n = 0; n < s.steps; ++n) sim.step();
    const double q = 1e4, kwn = 2e7 / 0.4, M = constrained_modulus(10e6, 0.3), p = q * kwn / (kwn + M);
    const Points& pt = sim.points();
    REQUIRE(pt.size() == 64);
    for (std::size_t k = 0; k < pt.size(); ++k) {
        CHECK(pt.pw[k] == approx(p).epsilon(0.01));
        // the total vertical stress carries q: sigma'_yy - p = -q, to eq. 8's volume (the
        // cell's sum over L^2 of points that shrank by the volumetric strain, 2e-4)
        CHECK(pt.syy[k] - pt.pw[k] == approx(-q).epsilon(0.01));
    }
    CHECK(sim.unbalanced_ratio() < 1e-6);
    const Simulation::Energy e = sim.energy();
    CHECK(e.w_loads > 0);
    CHECK(std::fabs(e.error) < 1e-3);  // the water's stored energy counted with the strain energy
}

TEST_CASE("a submerged column at rest: hydrostatic pore pressure and the buoyant weight on the skeleton") {
    // Water table at the top, the top drained: the skeleton, made stress-free with p
    // already hydrostatic, settles under its buoyant weight while the excess drains. Drained
    // by a DRAIN card on the lattice's top edge, or (the lattice a cell higher) through its
    // free top surface, a seepage face: the same answer.
    for (const bool seepage : {false, true}) {
    INFO("seepage face " << seepage);
    const Scene s = water_scene(std::string(seepage ? "GRID 1 11 0.2\n" : "GRID 1 10 0.2\nDRAIN 0 2 0.2 2\n") + R"(
MATERIAL 1 ELASTIC E=50E6 NU=0.3 RHO=2000 POROSITY=0.4 PERM=3.9E-4
WATER KW=2.2E8 TABLE=2
CLUSTER 1 0 0 0.2 2
FIX XY 0 0 0.2 0
FIX X 0 0 0 2.2
FIX X 0.2 0 0.2 2.2
GRAVITY 0 -9.81
DAMPING 0.8
STEP 1.5E-4 30000
)");
    Simulation sim(s);
    for (long n = 0; n < s.steps; ++n) sim.step();
    const double gw = 1000 * 9.81, gb = (2000 - 1000) * 9.81, H = 2;
    const Points& pt = sim.points();
    std::map<int, std::vector<std::size_t>> cells;
    for (std::size_t k = 0; k < pt.size(); ++k) {
        CHECK(pt.pw[k] == approx(gw * (H - pt.y[k])).epsilon(0.02));  // p at the point's own place
        cells[pt.cell[k]].push_back(k);
    }
    for (const auto& cell_points : cells) {  // sigma'_yy, one value a cell (eq. 5, 6), at the cell's points' mean depth
        const int c = cell_points.first;
        const std::vector<std::size_t>& ks = cell_points.second;
        double y = 0, syy = 0;
        for (std::size_t k : ks) { y += pt.y[k]; syy += pt.syy[k]; }
        y /= double(ks.size()); syy /= double(ks.size());
        INFO("cell " << c << " y " << y);
        CHECK(syy == approx(-gb * (H - y)).epsilon(0.02));
    }
    CHECK(sim.unbalanced_ratio() < 1e-6);
    CHECK(std::fabs(sim.excess_pressure()) < 0.01 * gw * H);
    CHECK(std::fabs(sim.energy().error) < 0.01);
    CHECK(sim.drained() > 0);  // water left, none came in
    }
}

// [slow]: 3.4 s at -O2, 73 s under the sanitizers, whose build runs the water's code on the
// cases above and below.
TEST_CASE("Terzaghi's consolidation (decks/consolidation.deck, 20 cells over H): the isochrones and the settlement, converging [slow]") {
    // The deck as shipped (10 cells over H) first: its RMS at each time, which the run at
    // 20 cells must halve, about (first order in L; make verify goes on to 40).
    std::vector<double> coarse;
    {
        Scene c;
        REQUIRE(read_deck("decks/consolidation.deck", c).empty());
        Simulation sim(c);
        const double M = constrained_modulus(10e6, 0.3), kwn = 2.2e8 / 0.4, cv = 9e-5 / (1000 * 9.81 * (1 / M + 1 / kwn)), p0 = 1e4 * kwn / (kwn + M);
        long done = 0;
        for (const double T : {0.05, 0.2, 0.5}) {
            const long to = std::lround(T * 4 / cv / c.dt_s);
            for (long n = done; n < to; ++n) sim.step();
            done = to;
            double sq = 0;
            for (std::size_t a = 0; a < sim.points().size(); ++a) {
                const double e = sim.points().pw[a] - terzaghi(p0, 2 - sim.points().y[a], 2, cv * sim.time() / 4);
                sq += e * e;
            }
            coarse.push_back(std::sqrt(sq / double(sim.points().size())) / p0);
        }
    }
    Scene s;
    REQUIRE(read_deck("decks/consolidation.deck", s).empty());
    refine(s, 2);
    REQUIRE(validate(s).empty());
    Simulation sim(s);
    std::size_t at = 0;
    const double E = 10e6, nu = 0.3, n = 0.4, kw = 2.2e8, k = 9e-5, H = 2, q = 1e4, gw = 1000 * 9.81;
    const double M = constrained_modulus(E, nu), kwn = kw / n, cv = k / (gw * (1 / M + 1 / kwn)), p0 = q * kwn / (kwn + M);
    const double L = s.cell_m, z0 = L / 4;
    long done = 0;
    for (const double T : {0.05, 0.2, 0.5}) {
        const long to = std::lround(T * H * H / cv / s.dt_s);
        for (long n = done; n < to; ++n) sim.step();
        done = to;
        const double t = sim.time(), Tv = cv * t / (H * H);
        const Points& pt = sim.points();
        double sq = 0, top = 0;
        int row = 0;
        for (std::size_t a = 0; a < pt.size(); ++a) {
            const double e = pt.pw[a] - terzaghi(p0, H - pt.y[a], H, Tv);
            sq += e * e;
            if (pt.y[a] > H - L / 2) { top += sim.initial_y()[std::size_t(pt.id[a])] - pt.y[a]; ++row; }  // the top row of points
        }
        const double rms = std::sqrt(sq / double(pt.size())) / p0;
        top /= row;
        // The top row lies z0 = L / 4 below the surface: its settlement is the strain
        // (q - p) / M integrated from z0 to H, the series' integral in closed form.
        double pz = 0;
        for (int i = 0; i < 400; ++i) { const double m = kPi * (2 * i + 1) / 2; pz += 2 * p0 * H / (m * m) * std::cos(m * z0 / H) * std::exp(-m * m * Tv); }
        const double settled = (q * (H - z0) - pz) / M;
        MESSAGE("T_v " << Tv << ": RMS " << rms << " of p0; settlement " << top << " m against " << settled << " m");
        CHECK(rms < 0.03);
        CHECK(rms < 0.7 * coarse[at++]);  // 10 cells over H: 3.4, 2.2, 1.0 % (the ratio 0.50 measured at each time)
        CHECK(top == approx(settled).epsilon(0.01));
    }
}

TEST_CASE("the flow keeps the water's volume: a closed box, half above its water table") {
    // Every node held: the points' volumes never change, so p changes by the flow alone,
    // and sum V n p / KW (no drain) must stay what it was, to rounding.
    const Scene s = water_scene(R"(GRID 4 8 0.25
MATERIAL 1 ELASTIC E=50E6 NU=0.3 RHO=2000 POROSITY=0.3 PERM=1E-4
MATERIAL 2 ELASTIC E=50E6 NU=0.3 RHO=2000 POROSITY=0.45 PERM=1E-6
WATER KW=2.2E8 TABLE=1
CLUSTER 1 0 0 1 2
CLUSTER 2 0.5 0.5 1 1.5
FIX XY 0 0 1 2
GRAVITY 0 -9.81
STEP 1E-4 2000
)");
    Simulation sim(s);
    auto water = [&] {
        const Points& pt = sim.points();
        double w = 0;
        for (std::size_t k = 0; k < pt.size(); ++k) w += pt.vol[k] * (sim.material_id(k) == 1 ? 0.3 : 0.45) * pt.pw[k] / 2.2e8;
        return w;
    };
    const double before = water();
    const std::vector<double> p0 = sim.points().pw;
    for (long n = 0; n < s.steps; ++n) sim.step();
    const double after = water();
    CHECK(sim.points().pw != p0);  // it flowed
    CHECK(std::fabs(after - before) < 1e-12 * before);
    CHECK(sim.drained() == 0);
}

TEST_CASE("the deck's checks of WATER, DRAIN and LOAD") {
    const std::string base = "GRID 2 8 0.25\nCLUSTER 1 0 0 0.5 2\nFIX XY 0 0 0.5 0\nSTEP 1E-4 10\n";
    CHECK(water_errors(base + "MATERIAL 1 ELASTIC E=1E7 NU=0.3 RHO=2000 POROSITY=0.4\n").find("water.deck:5:1: error: POROSITY makes the material saturated: the deck needs a WATER card") != std::string::npos);
    CHECK(water_errors(base + "MATERIAL 1 ELASTIC E=1E7 NU=0.3 RHO=2000\nWATER\n").find("water.deck:6:1: error: WATER, but no MATERIAL has POROSITY") != std::string::npos);
    CHECK(water_errors(base + "MATERIAL 1 ELASTIC E=1E7 NU=0.3 RHO=2000 POROSITY=1.2\nWATER\n").find("POROSITY") != std::string::npos);
    CHECK(water_errors(base + "MATERIAL 1 ELASTIC E=1E7 NU=0.3 RHO=2000 POROSITY=0.4\nWATER UNDRAINED UNDRAINED\n").find("water.deck:6:17: error: UNDRAINED is given twice") != std::string::npos);
    CHECK(water_errors(base + "MATERIAL 1 ELASTIC E=1E7 NU=0.3 RHO=2000 POROSITY=0.4\nWATER KW=1E9 TABLE=3 UNDRAINED\nDRAIN 0 2 0.5 2\n").find("water.deck:7:1: error: DRAIN with WATER UNDRAINED") != std::string::npos);
    CHECK(water_errors(base + "MATERIAL 1 ELASTIC E=1E7 NU=0.3 RHO=2000\nLOAD 0 0 0.5 2 TY=-1\n").find("water.deck:6:1: error: a LOAD is a line") != std::string::npos);
    // the flow's own limit, n L^2 gamma_w / (8 KW k) without drains: 1.39e-5 s here
    const std::string quick = water_errors(base + "MATERIAL 1 ELASTIC E=1E7 NU=0.3 RHO=2000 POROSITY=0.4 PERM=1E-2\nWATER KW=2.2E8\n");
    CHECK(quick.find("water.deck:4:1: error: time step 0.0001 s is above the pore water's stable limit 1.39347e-05 s (n L^2 gamma_w / (8 KW PERM)") != std::string::npos);
    CHECK(water_errors(base + "MATERIAL 1 ELASTIC E=1E7 NU=0.3 RHO=2000 POROSITY=0.4 PERM=1E-4\nWATER KW=2.2E8 TABLE=1.5\nDRAIN 0 2 0.5 2\nLOAD 0 2 0.5 2 TY=-1E4\n").empty());
}

TEST_CASE("Terzaghi's consolidation converges as L halves: 10, 20, 40 cells over H [slow][verify]") {
    const double E = 10e6, nu = 0.3, n = 0.4, kw = 2.2e8, k = 9e-5, H = 2, q = 1e4, gw = 1000 * 9.81;
    const double M = constrained_modulus(E, nu), kwn = kw / n, cv = k / (gw * (1 / M + 1 / kwn)), p0 = q * kwn / (kwn + M);
    double last[3] = {0, 0, 0};
    for (const int r : {1, 2, 4}) {
        Scene s;
        REQUIRE(read_deck("decks/consolidation.deck", s).empty());
        refine(s, r);
        Simulation sim(s);
        long done = 0;
        int at = 0;
        for (const double T : {0.05, 0.2, 0.5}) {
            const long to = std::lround(T * H * H / cv / s.dt_s);
            for (long m = done; m < to; ++m) sim.step();
            done = to;
            const Points& pt = sim.points();
            double sq = 0;
            for (std::size_t a = 0; a < pt.size(); ++a) {
                const double e = pt.pw[a] - terzaghi(p0, H - pt.y[a], H, cv * sim.time() / (H * H));
                sq += e * e;
            }
            const double rms = std::sqrt(sq / double(pt.size())) / p0;
            MESSAGE((10 * r) << " cells over H, T_v " << T << ": RMS " << rms << " of p0");
            if (r > 1) CHECK(rms < 0.75 * last[at]);  // first order: about half each time L halves (0.54-0.67 measured)
            last[at++] = rms;
        }
    }
}

TEST_CASE("GEOSTATIC: level ground starts in equilibrium, dry and below a water table") {
    // sigma'_yy = -(rho g z) above the table, -(rho g (H - T) + (rho - rho_w) g (T - y))
    // below, sigma'_xx = nu / (1 - nu) sigma'_yy: the first step's forces balance to rounding.
    for (const bool wet : {false, true}) {
        std::string text = "GRID 3 12 0.25\nCLUSTER 1 0 0 0.75 3\nFIX XY 0 0 0.75 0\nFIX X 0 0 0 3\nFIX X 0.75 0 0.75 3\n"
                           "GRAVITY 0 -9.81\nGEOSTATIC\nSTEP 1E-4 20\n";
        text += wet ? "MATERIAL 1 MOHR E=2E7 NU=0.25 RHO=2000 PHI=30 C=1000 POROSITY=0.4 PERM=1E-6\nWATER KW=2E8 TABLE=2\n"
                    : "MATERIAL 1 MOHR E=2E7 NU=0.25 RHO=2000 PHI=30 C=1000\n";
        const Scene s = water_scene(text);
        Simulation sim(s);
        const Points& pt = sim.points();
        const double g = 9.81, H = 3, T = 2;
        for (std::size_t k = 0; k < pt.size(); ++k) {
            const double y = pt.y[k];
            const double syy = !wet || y >= T ? -2000 * g * (H - y) : -2000 * g * (H - T) - 1000 * g * (T - y);
            INFO("wet " << wet << " y " << y);
            CHECK(pt.syy[k] == approx(syy).epsilon(1e-12));
            CHECK(pt.sxx[k] == approx(syy / 3).epsilon(1e-12));
            CHECK(pt.szz[k] == pt.sxx[k]);
        }
        for (int n = 0; n < 20; ++n) sim.step();
        CHECK(sim.unbalanced_ratio() < 1e-9);  // at rest from the first step
        // nothing moves, so no energy is made or lost: the account's rounding (the flow's
        // stored energy, 6e-16 J/m here) is not "100 % of the energy in play"
        CHECK(std::fabs(sim.energy().error) < 1e-9);
    }
}

TEST_CASE("RESERVOIR: a submerged block under a metre of water, and a drawdown that fails a slope [slow]") {
    SUBCASE("the reservoir's pressure on the top and the drained surface: p hydrostatic to its level") {
        // GEOSTATIC starts the skeleton at its buoyant weight: it has only the reservoir's
        // top pressure to settle, which p takes and the drained top lets go.
        const Scene s = water_scene(R"(GRID 2 20 0.2
MATERIAL 1 ELASTIC E=50E6 NU=0.3 RHO=2000 POROSITY=0.4 PERM=3.9E-4
WATER KW=2.2E8 TABLE=3
RESERVOIR 3
CLUSTER 1 0 0 0.4 2
FIX XY 0 0 0.4 0
FIX X 0 0 0 4
FIX X 0.4 0 0.4 4
GRAVITY 0 -9.81
GEOSTATIC
DAMPING 0.8
STEP 1.5E-4 5000
)");
        Simulation sim(s);
        for (long n = 0; n < s.steps; ++n) sim.step();
        const Points& pt = sim.points();
        std::map<int, std::vector<std::size_t>> cells;
        for (std::size_t k = 0; k < pt.size(); ++k) {
            CHECK(pt.pw[k] == approx(1000 * 9.81 * (3 - pt.y[k])).epsilon(0.01));
            cells[pt.cell[k]].push_back(k);
        }
        for (const auto& cell_points : cells) {  // the block's buoyant weight on the skeleton; the water above weighs on p alone
            const std::vector<std::size_t>& ks = cell_points.second;
            double y = 0, syy = 0;
            for (std::size_t k : ks) { y += pt.y[k]; syy += pt.syy[k]; }
            y /= double(ks.size()); syy /= double(ks.size());
            CHECK(syy == approx(-1000 * 9.81 * (2 - y)).epsilon(0.01));
        }
        CHECK(sim.unbalanced_ratio() < 1e-6);
        // the reservoir's pressure on the top, rho_w g 1 m x 0.4 m, is part of the base's reaction
        CHECK(sim.reaction_y() == approx(2000 * 9.81 * 0.8 + 1000 * 9.81 * 0.4).epsilon(1e-3));
    }
    SUBCASE("drawdown.deck at L = 1 m: it stands with its reservoir, and slides when the reservoir falls") {
        for (const bool falls : {false, true}) {
            Scene s;
            REQUIRE(read_deck("decks/drawdown.deck", s).empty());
            // twice as coarse: L = 1 m, 816 points, dt doubled (the flow's limit allows it)
            s.mx /= 2; s.my /= 2; s.cell_m *= 2; s.dt_s *= 2; s.steps /= 2;
            s.outputs.clear();
            if (!falls) s.reservoir.to = s.reservoir.level;
            REQUIRE(validate(s).empty());
            Simulation sim(s);
            const long before = std::lround(s.reservoir.start / s.dt_s);
            for (long n = 0; n < before; ++n) sim.step();
            CHECK(sim.unbalanced_ratio() < 1e-3);  // at rest under the full reservoir
            auto face_x = [&] { return sim.points().x[std::size_t(sim.slot_of(sim.tracked()[1]))]; };  // (the storage is sorted now and then)
            const double x_before = face_x();
            for (long n = before; n < s.steps; ++n) sim.step();
            const double moved = face_x() - x_before;
            MESSAGE(std::string(falls ? "drawdown" : "reservoir kept") << ": the face moved " << moved << " m, unbalanced " << sim.unbalanced_ratio());
            if (falls) {
                CHECK(moved > 0.5);  // it slides (measured 1.3 m in the 5.5 s after, and moving)
                CHECK(sim.unbalanced_ratio() > 1e-2);
            } else {
                CHECK(std::fabs(moved) < 0.01);
                CHECK(sim.unbalanced_ratio() < 1e-4);
            }
            CHECK(std::fabs(sim.energy().error) < 0.1);
        }
    }
    // drawdown.deck at L = 1 m under MAPPING SMOOTH, its reservoir kept, over the 4 s
    // before the drawdown would start: the face's move, the account, the water drawn in.
    struct Standing { double moved, error, drained; };
    auto standing = [](Advect a) {
        Scene s;
        REQUIRE(read_deck("decks/drawdown.deck", s).empty());
        s.mx /= 2; s.my /= 2; s.cell_m *= 2; s.dt_s *= 2;
        s.outputs.clear();
        s.mapping = Mapping::Smooth;
        s.advect = a;
        s.reservoir.to = s.reservoir.level;
        REQUIRE(validate(s).empty());
        Simulation sim(s);
        const double x0 = sim.points().x[std::size_t(sim.slot_of(sim.tracked()[1]))];
        const long steps = std::lround(s.reservoir.start / s.dt_s);
        for (long n = 0; n < steps; ++n) sim.step();
        const double moved = sim.points().x[std::size_t(sim.slot_of(sim.tracked()[1]))] - x0;
        return Standing{moved, sim.energy().error, sim.drained()};
    };
    SUBCASE("drawdown.deck at L = 1 m with MAPPING SMOOTH and ADVECT FLIP: it stands under its reservoir, the energy account closed") {
        // The material's faces are the edges of the cells holding points: when a cell that
        // held only a sliver of a square counted, the reservoir's pressure on its nodes (of
        // that sliver's mass) moved one 80 m in the second step.
        const Standing r = standing(Advect::Flip);
        MESSAGE("SMOOTH + FLIP, reservoir kept: the face moved " << r.moved << " m, energy error " << r.error << ", drained " << r.drained);
        CHECK(std::fabs(r.moved) < 0.01);   // measured 3 mm, as with the paper's mapping
        CHECK(std::fabs(r.error) < 1e-3);   // measured 4e-5
        CHECK(r.drained > -0.002);          // little water enters (0.0008 m^3/m in 4 s)
    }
    SUBCASE("drawdown.deck at L = 1 m with MAPPING SMOOTH and no ADVECT FLIP draws water in through its faces (the reader's warning)") {
        // The reservoir's pressure misses the parts of squares past the material's faces
        // (the warning's words): the faces swell and draw water in, 56 times what FLIP lets in
        // (measured 0.045 m^3/m in 4 s; 0.11 at L = 0.5 m, where the crest then settles
        // 1.26 m against FLIP's 0.64 m). Should a cure come, this says the warning can go.
        const Standing r = standing(Advect::Eq12);
        MESSAGE("SMOOTH without FLIP, reservoir kept: the face moved " << r.moved << " m, energy error " << r.error << ", drained " << r.drained);
        CHECK(r.drained < -0.01);
    }
}

TEST_CASE("the deck's checks of RESERVOIR and GEOSTATIC") {
    {  // --set on a card the deck does not have changes nothing, and says so
        Scene sc;
        REQUIRE(read_deck("decks/column.deck", sc).empty());
        CHECK(apply_setting(sc, "WATER.KW", 1e9) == "the deck has no WATER card: WATER.KW would change nothing");
        CHECK(apply_setting(sc, "reservoir.to", 3) == "the deck has no RESERVOIR card: reservoir.to would change nothing");
        CHECK(apply_setting(sc, "GEOSTATIC.K0", 0.5) == "the deck has no GEOSTATIC card: GEOSTATIC.K0 would change nothing");
        Scene dd;
        REQUIRE(read_deck("decks/drawdown.deck", dd).empty());
        CHECK(apply_setting(dd, "RESERVOIR.TO", 10) == "");
        CHECK(dd.reservoir.to == 10);
        // MAPPING SMOOTH without ADVECT FLIP under a reservoir: a warning at the RESERVOIR
        // card (the faces draw water in: decks/README); with FLIP, or the paper's mapping, none
        auto flip_warning = [&](Mapping m, Advect a) {
            Scene w = dd;
            w.mapping = m;
            w.advect = a;
            for (const auto& x : warnings(w))
                if (x.str().find("add ADVECT FLIP") != std::string::npos) return x.str();
            return std::string();
        };
        CHECK(flip_warning(Mapping::Smooth, Advect::Eq12).find("decks/drawdown.deck:13:1: warning: with MAPPING SMOOTH and no ADVECT FLIP") == 0);
        CHECK(flip_warning(Mapping::Smooth, Advect::Flip).empty());
        CHECK(flip_warning(Mapping::Paper, Advect::Eq12).empty());
    }
    const std::string base = "GRID 2 8 0.25\nCLUSTER 1 0 0 0.5 2\nFIX XY 0 0 0.5 0\nSTEP 1E-4 10\nMATERIAL 1 ELASTIC E=1E7 NU=0.3 RHO=2000\n";
    CHECK(water_errors(base + "GRAVITY 0 -9.81\nRESERVOIR 3\n").find("water.deck:7:1: error: RESERVOIR needs a WATER card") != std::string::npos);
    CHECK(water_errors(base + "GEOSTATIC\n").find("water.deck:6:1: error: GEOSTATIC needs gravity straight down") != std::string::npos);
    CHECK(water_errors(base + "GRAVITY 0 -9.81\nGEOSTATIC K0=-1\n").find("K0") != std::string::npos);
    CHECK(water_errors(base + "GRAVITY 0 -9.81\nGEOSTATIC K0=0.5\nRESERVOIR 3 TO=1 START=1 OVER=2\n").find("RESERVOIR needs a WATER") != std::string::npos);
}

TEST_CASE("--fos on a saturated slope: drawdown.deck at L = 1 m, full reservoir against the state after a rapid drawdown [slow]") {
    // The same slope and strength: under its full reservoir it stands with a margin; with
    // the water outside at the toe and the pores still full to the crest (undrained, the
    // moment after a rapid drawdown) it has none. Measured at L = 0.5 m: 1.78 and 0.67.
    double F[2] = {0, 0};
    for (const bool after : {false, true}) {
        Scene s;
        REQUIRE(read_deck("decks/drawdown.deck", s).empty());
        s.mx /= 2; s.my /= 2; s.cell_m *= 2; s.dt_s *= 2; s.steps /= 2;
        s.outputs.clear();
        s.reservoir.level = s.reservoir.to = after ? 2 : 10;
        REQUIRE(validate(s).empty());
        FosOptions o;
        o.tol = 0.02;
        const FosResult r = factor_of_safety(s, o);
        REQUIRE(r.outcome == FosResult::Found);
        F[after] = r.F;
        MESSAGE(std::string(after ? "after the drawdown" : "full reservoir") << ": F = " << r.F << " (" << r.trials.size() << " trials)");
    }
    CHECK(F[0] > 1.3);
    CHECK(F[1] < 0.9);
    CHECK(F[1] < 0.6 * F[0]);
}
