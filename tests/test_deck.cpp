// The deck reader: every card into the Scene, every lexical rule, and
// every error with the line and column it is reported at. Each test is a small deck
// read as if from the file "t.deck".
#include <doctest/doctest.h>

#include "../lpfdm.hpp"
#include "common.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <sstream>
#include <filesystem>
#include <fstream>
#include <functional>
#include <string>

#include <unistd.h>

namespace {

using lpfdm::Diagnostics;
using lpfdm::Scene;

// The smallest runnable scene, one card per line (lines 1 to 4). Tests append a card
// (it becomes line 5) or replace one of these lines.
const std::string kGrid = "GRID 4 4 1\n";
const std::string kMaterial = "MATERIAL 1 ELASTIC E=5E7 NU=0.3 RHO=2000\n";
const std::string kCluster = "CLUSTER 1 0 0 2 2\n";
const std::string kStep = "STEP 1E-4 10\n";
const std::string kBase = kGrid + kMaterial + kCluster + kStep;

// The base scene with one more card on line 5.
std::string plus(const std::string& card) { return kBase + card + "\n"; }

Diagnostics read_text(const std::string& deck, Scene& s) { return lpfdm::read_deck_text(deck, "t.deck", s); }

std::string listing(const Diagnostics& d) {
    std::string out = d.empty() ? "(no diagnostics)" : "";
    for (const auto& e : d) out += e.str() + "\n";
    return out;
}

bool has(const std::string& text, const std::string& phrase) { return text.find(phrase) != std::string::npos; }

// A deck that must read without any diagnostic.
Scene read_ok(const std::string& deck) {
    Scene s;
    const Diagnostics d = read_text(deck, s);
    INFO(listing(d));
    CHECK(d.empty());
    return s;
}

}  // namespace

// Exactly one error (one message per problem), at LINE:COL of t.deck, whose message
// contains PHRASE.
#define CHECK_ONE_ERROR(deck, LINE, COL, PHRASE)             \
    do {                                                     \
        lpfdm::Scene s_;                                     \
        const lpfdm::Diagnostics d_ = read_text((deck), s_); \
        INFO(listing(d_));                                   \
        REQUIRE(d_.size() == 1);                             \
        CHECK(d_[0].pos.file == "t.deck");                   \
        CHECK(d_[0].pos.line == (LINE));                     \
        CHECK(d_[0].pos.col == (COL));                       \
        CHECK(has(d_[0].message, (PHRASE)));                 \
    } while (0)

// ================================================================ cards ===

TEST_CASE("deck: the base scene of these tests reads without a message") {
    const Scene s = read_ok(kBase);
    CHECK(s.mx == 4);
    CHECK(s.steps == 10);
}

TEST_CASE("deck: TITLE keeps the rest of its line, without the comment and outer blanks") {
    const Scene s = read_ok("TITLE   Sand heap, dry = 2 layers  ! first try\n" + kBase);
    CHECK(s.title == "Sand heap, dry = 2 layers");
    CHECK(read_ok("TITLE\n" + kBase).title.empty());
    CHECK(read_ok(kBase).title.empty());
}

TEST_CASE("deck: GRID gives the cells in x and y and the cell side") {
    const Scene s = read_ok("GRID 40 24 0.5\n" + kMaterial + kCluster + kStep);
    CHECK(s.mx == 40);
    CHECK(s.my == 24);
    CHECK(s.cell_m == 0.5);
    CHECK(s.grid_pos.file == "t.deck");
    CHECK(s.grid_pos.line == 1);
    CHECK(s.grid_pos.col == 1);
}

TEST_CASE("deck: MATERIAL ELASTIC gives E, NU and RHO") {
    const Scene s = read_ok(plus("MATERIAL 7 ELASTIC E=2E7 NU=0.25 RHO=1800"));
    REQUIRE(s.materials.size() == 2);
    const lpfdm::Material& m = s.materials[1];
    CHECK(m.id == 7);
    CHECK(m.model == lpfdm::Model::Elastic);
    CHECK(m.E == 2e7);
    CHECK(m.nu == 0.25);
    CHECK(m.rho == 1800);
    CHECK(m.pos.line == 5);
    CHECK(m.pos.col == 1);
    CHECK(s.material(7) == &m);
}

TEST_CASE("deck: MATERIAL MOHR with every parameter") {
    const Scene s = read_ok(plus("MATERIAL 2 MOHR E=5E7 NU=0.3 RHO=1900 PHI=35 C=1E3 PSI=5 TENSION=500 SOFTEN=0.5 SCATTER=0.2"));
    REQUIRE(s.materials.size() == 2);
    const lpfdm::Material& m = s.materials[1];
    CHECK(m.id == 2);
    CHECK(m.model == lpfdm::Model::MohrCoulomb);
    CHECK(m.E == 5e7);
    CHECK(m.nu == 0.3);
    CHECK(m.rho == 1900);
    CHECK(m.phi_deg == 35);
    CHECK(m.c == 1e3);
    CHECK(m.psi_deg == 5);
    CHECK(m.tension == 500);
    CHECK(m.soften == 0.5);
    CHECK(m.scatter == 0.2);
}

TEST_CASE("deck: MATERIAL MOHR defaults: PSI=0, tension limited by the apex only, SOFTEN=0, SCATTER=0") {
    const Scene s = read_ok(plus("MATERIAL 2 MOHR E=5E7 NU=0.3 RHO=1900 PHI=30 C=0"));
    REQUIRE(s.materials.size() == 2);
    const lpfdm::Material& m = s.materials[1];
    CHECK(m.phi_deg == 30);
    CHECK(m.c == 0);
    CHECK(m.psi_deg == 0);
    CHECK(m.tension == -1);  // < 0: the apex c / tan(phi)
    CHECK(m.soften == 0);
    CHECK(m.scatter == 0);
}

TEST_CASE("deck: MATERIAL parameters may come in any order") {
    const Scene s = read_ok(plus("MATERIAL 2 MOHR C=10 PSI=20 RHO=1900 PHI=30 NU=0.3 E=5E7"));
    REQUIRE(s.materials.size() == 2);
    CHECK(s.materials[1].psi_deg == 20);  // PSI <= PHI although PHI comes later
    CHECK(s.materials[1].c == 10);
}

TEST_CASE("deck: CLUSTER takes a material, a box and PPC=2 unless given") {
    const Scene s = read_ok(kGrid + kMaterial + "CLUSTER 1 0 0 2 2\nCLUSTER 1 2 0 4 1.5 PPC=3\n" + kStep);
    REQUIRE(s.clusters.size() == 2);
    const lpfdm::Cluster& a = s.clusters[0];
    CHECK(a.mat == 1);
    CHECK(a.box.x0 == 0);
    CHECK(a.box.y0 == 0);
    CHECK(a.box.x1 == 2);
    CHECK(a.box.y1 == 2);
    CHECK(a.ppc == 2);
    CHECK(a.pos.line == 3);
    const lpfdm::Cluster& b = s.clusters[1];
    CHECK(b.box.x0 == 2);
    CHECK(b.box.y1 == 1.5);
    CHECK(b.ppc == 3);
    CHECK(b.pos.line == 4);
}

// ============================================================ POLYGON ===

namespace {
// The cells (j mx + i) cluster k of s fills, in order.
std::vector<int> cells_of(const Scene& s, std::size_t k) {
    std::vector<int> v;
    lpfdm::detail::cluster_cells(s.clusters.at(k), s.cell_m, s.mx, s.my, [&](int i0, int i1, int j) {
        for (int i = i0; i <= i1; ++i) v.push_back(j * s.mx + i);
    });
    return v;
}
// The cells a whole scene's clusters fill, each once, in order.
std::vector<int> all_cells(const Scene& s) {
    std::vector<char> in(std::size_t(s.mx) * s.my, 0);
    for (std::size_t k = 0; k < s.clusters.size(); ++k)
        for (int c : cells_of(s, k)) in[std::size_t(c)] = 1;
    std::vector<int> v;
    for (std::size_t c = 0; c < in.size(); ++c)
        if (in[c]) v.push_back(int(c));
    return v;
}
}  // namespace

TEST_CASE("deck: CLUSTER mat POLYGON x1 y1 x2 y2 ... takes the vertices, their places and PPC") {
    const Scene s = read_ok(kGrid + kMaterial + "CLUSTER 1 polygon 0 0 2 0 2 2 0 2 PPC=3\n" + kStep);
    REQUIRE(s.clusters.size() == 1);
    const lpfdm::Cluster& c = s.clusters[0];
    CHECK(c.mat == 1);
    CHECK(c.ppc == 3);
    CHECK(c.polygon == std::vector<double>{0, 0, 2, 0, 2, 2, 0, 2});
    REQUIRE(c.polygon_pos.size() == 8);
    CHECK(c.polygon_pos[2].line == 3);
    CHECK(c.polygon_pos[2].col == 23);
    CHECK(lpfdm::count_points(s) == 4 * 9);
}

// A centre on an edge of the polygon (or within L/1000 of it in x and in y) counts as
// inside, as a box's does: a polygon with a box's corners, in either orientation and
// starting at any corner, fills the box's cells, also where its edges pass through
// centres, lie a thousandth of a cell from them, or the box is a line.
TEST_CASE("deck: a POLYGON with a box's corners fills exactly the box's cells, in either orientation") {
    const char* boxes[] = {"0 0 4 4", "0.5 0.5 1.5 1.5", "0.25 0.25 2.75 1.75", "0.2495 0.5 1.7505 3.2", "0.2515 0.5 1.7485 3.2",
                           "1 1 3 1.25", "0 0 2.3 0.9", "1.25 0.25 1.5 3.75"};
    for (const char* b : boxes) {
        double x0, y0, x1, y1;
        REQUIRE(std::sscanf(b, "%lf %lf %lf %lf", &x0, &y0, &x1, &y1) == 4);
        auto num = [](double v) { return lpfdm::shortest(v); };
        const std::string X0 = num(x0), Y0 = num(y0), X1 = num(x1), Y1 = num(y1);
        const std::string ccw = X0 + " " + Y0 + " " + X1 + " " + Y0 + " " + X1 + " " + Y1 + " " + X0 + " " + Y1;
        const std::string cw = X1 + " " + Y1 + " " + X1 + " " + Y0 + " " + X0 + " " + Y0 + " " + X0 + " " + Y1;
        const Scene box = read_ok("GRID 8 8 0.5\n" + kMaterial + "CLUSTER 1 " + b + "\n" + kStep);
        const Scene p1 = read_ok("GRID 8 8 0.5\n" + kMaterial + "CLUSTER 1 POLYGON " + ccw + "\n" + kStep);
        const Scene p2 = read_ok("GRID 8 8 0.5\n" + kMaterial + "CLUSTER 1 POLYGON " + cw + "\n" + kStep);
        INFO("box " << std::string(b));
        CHECK(!cells_of(box, 0).empty());
        CHECK(cells_of(p1, 0) == cells_of(box, 0));
        CHECK(cells_of(p2, 0) == cells_of(box, 0));
        CHECK(lpfdm::count_points(p1) == lpfdm::count_points(box));
    }
}

TEST_CASE("deck: a concave POLYGON (an L) fills the cells whose centres lie inside it") {
    const Scene s = read_ok(kGrid + kMaterial + "CLUSTER 1 POLYGON 0 0 4 0 4 1 1 1 1 4 0 4 PPC=1\n" + kStep);
    // Row 0 whole, then column 0: the centres (1.5, 1.5) ... lie outside the notch's edges.
    CHECK(cells_of(s, 0) == std::vector<int>{0, 1, 2, 3, 4, 8, 12});
    // The same L clockwise, from another vertex.
    const Scene t = read_ok(kGrid + kMaterial + "CLUSTER 1 POLYGON 1 4 1 1 4 1 4 0 0 0 0 4 PPC=1\n" + kStep);
    CHECK(cells_of(t, 0) == cells_of(s, 0));
    // An edge through a row of centres takes them: the notch's corner at (1.5, 1.5).
    const Scene u = read_ok(kGrid + kMaterial + "CLUSTER 1 POLYGON 0 0 4 0 4 1.5 1.5 1.5 1.5 4 0 4 PPC=1\n" + kStep);
    CHECK(cells_of(u, 0) == std::vector<int>{0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 12, 13});
}

// decks/quake_slope.deck's slope, once a staircase of 13 boxes: the face from (12, 0) to
// (6, 6) passes through the centres of the cells the staircase ended with, so the
// polygon fills the same cells; and the staircase's own outline (50 vertices, over
// continuation lines) fills them too.
TEST_CASE("deck: a 45 degree POLYGON fills the staircase of boxes it replaced; 50 vertices over & lines") {
    std::string boxes = "CLUSTER 1 0 0 6 6\n";
    for (int j = 0; j < 12; ++j)
        boxes += "CLUSTER 1 6 " + lpfdm::shortest(0.5 * j) + " " + lpfdm::shortest(11.75 - 0.5 * j) + " " + lpfdm::shortest(0.5 * j + 0.5) + "\n";
    const std::string grid = "GRID 40 16 0.5\n" + kMaterial;
    const Scene stairs = read_ok(grid + boxes + kStep);
    const Scene slope = read_ok(grid + "CLUSTER 1 POLYGON 0 0  12 0  6 6  0 6\n" + kStep);
    CHECK(all_cells(stairs).size() == 144 + 78);
    CHECK(cells_of(slope, 0) == all_cells(stairs));
    // The outline, a step of 0.5 m per row, up 24 rows of a finer lattice: 50 vertices,
    // 4 to a line.
    std::vector<double> v = {0, 0, 12, 0};
    for (int j = 0; j < 24; ++j) {
        const double y = 0.25 * (j + 1), x = 12 - 0.25 * j;
        v.insert(v.end(), {x, y, x - 0.25, y});
    }
    v.back() = 6;  // the last step's top, x = 6
    v.insert(v.end(), {0, 6});
    v.erase(v.end() - 4, v.end() - 2);  // (6, 6) follows (6.25, 6): one vertex, not two
    REQUIRE(v.size() == 100);
    std::string card = "CLUSTER 1 POLYGON";
    for (std::size_t k = 0; k < v.size(); ++k) card += (k % 8 == 0 ? " &\n  " : " ") + lpfdm::shortest(v[k]);
    std::string fine_boxes = "CLUSTER 1 0 0 6 6\n";
    for (int j = 0; j < 24; ++j)
        fine_boxes += "CLUSTER 1 6 " + lpfdm::shortest(0.25 * j) + " " + lpfdm::shortest(12 - 0.25 * j) + " " + lpfdm::shortest(0.25 * j + 0.25) + "\n";
    const std::string fine = "GRID 80 32 0.25\n" + kMaterial;
    const Scene outline = read_ok(fine + card + "\n" + kStep);
    REQUIRE(outline.clusters.size() == 1);
    CHECK(outline.clusters[0].polygon == v);
    CHECK(outline.clusters[0].polygon_pos.back().line == 3 + 13);  // the 13th continuation line
    CHECK(cells_of(outline, 0) == all_cells(read_ok(fine + fine_boxes + kStep)));
}

TEST_CASE("deck: a later cluster replaces an earlier one in a cell, polygon or box") {
    const std::string mats = "MATERIAL 1 ELASTIC E=5E7 NU=0.3 RHO=2000\nMATERIAL 2 ELASTIC E=5E7 NU=0.3 RHO=1000\n";
    auto materials = [](const Scene& s) {  // the material id of each cell's points, by cell
        lpfdm::Simulation sim(s);
        std::vector<int> m(std::size_t(s.mx * s.my), 0);
        const lpfdm::Points& p = sim.points();
        for (std::size_t k = 0; k < p.x.size(); ++k)
            m[std::size_t(int(p.y[k] / s.cell_m) * s.mx + int(p.x[k] / s.cell_m))] = s.materials[std::size_t(sim.groups()[p.group[k]].mat_index)].id;
        return m;
    };
    const Scene a = read_ok(kGrid + mats + "CLUSTER 1 0 0 4 4\nCLUSTER 2 POLYGON 0 0 4 0 0 4\n" + kStep);
    const Scene b = read_ok(kGrid + mats + "CLUSTER 2 POLYGON 0 0 4 0 0 4\nCLUSTER 1 1 1 4 4\n" + kStep);
    CHECK(lpfdm::count_points(a) == 64);
    CHECK(materials(a) == std::vector<int>{2, 2, 2, 2, 2, 2, 2, 1, 2, 2, 1, 1, 2, 1, 1, 1});
    CHECK(materials(b) == std::vector<int>{2, 2, 2, 2, 2, 1, 1, 1, 2, 1, 1, 1, 2, 1, 1, 1});
}

TEST_CASE("deck error: a POLYGON's count of numbers, at the word POLYGON or the odd number") {
    CHECK_ONE_ERROR(plus("CLUSTER 1 POLYGON 0 0 2 2"), 5, 11, "a polygon needs at least 3 vertices (x y pairs); this one has 2");
    CHECK_ONE_ERROR(plus("CLUSTER 1 POLYGON PPC=2"), 5, 11, "a polygon needs at least 3 vertices (x y pairs); this one has 0");
    CHECK_ONE_ERROR(plus("CLUSTER 1 POLYGON 0 0 2 0 2 2 0 PPC=2"), 5, 31, "vertex 4 has an x but no y: a polygon takes x y pairs (7 numbers given)");
    CHECK_ONE_ERROR(plus("CLUSTER 1 POLYGON 0 0 2 0 2 x"), 5, 29, "vertex 3 y: expected a number, found 'x'");
    CHECK_ONE_ERROR(plus("CLUSTER 1 POLYGON 0 0 2 0 2 2 PCC=2"), 5, 31, "unknown parameter 'PCC'");
    CHECK_ONE_ERROR(plus("CLUSTER 9 POLYGON 0 0 2 0 2 2"), 5, 1, "material 9 is not defined");
}

TEST_CASE("deck error: a POLYGON's vertex repeated, no area, crossing itself: at the vertex") {
    CHECK_ONE_ERROR(plus("CLUSTER 1 POLYGON 0 0 2 0 2 0 2 2"), 5, 27, "vertex 3 (2, 0) repeats the vertex before it");
    CHECK_ONE_ERROR(plus("CLUSTER 1 POLYGON 0 0 2 0 2 2 0 2 0 0"), 5, 35, "the last vertex (0, 0) repeats the first: a polygon closes by itself");
    CHECK_ONE_ERROR(plus("CLUSTER 1 POLYGON 0 0 1 1 3 3"), 5, 1, "the polygon has no area: its vertices lie on one line");
    CHECK_ONE_ERROR(plus("CLUSTER 1 POLYGON 0 0 3 0 1 0"), 5, 1, "the polygon has no area");
    // A bow tie: the edge from vertex 3 to vertex 4 crosses the first; at vertex 4's x, on its line.
    CHECK_ONE_ERROR(plus("CLUSTER 1 POLYGON 1 1 3 3 &\n  3 1 1 3"), 6, 7,
                    "the polygon crosses itself: the edge from vertex 3 to vertex 4 meets the edge from vertex 1 to vertex 2");
    // Where it first crosses: the end of the first edge that meets an earlier one.
    CHECK_ONE_ERROR(plus("CLUSTER 1 POLYGON 0 0 4 0 4 3 1 3 1 1 3 4"), 5, 39,
                    "the polygon crosses itself: the edge from vertex 5 to vertex 6 meets the edge from vertex 3 to vertex 4");
    // Only the edge back from the last vertex to the first crosses: at the last vertex.
    CHECK_ONE_ERROR(plus("CLUSTER 1 POLYGON 0 0 2 0 2 3 3 3 3 1"), 5, 35,
                    "the polygon crosses itself: the edge from vertex 5 back to vertex 1 meets the edge from vertex 2 to vertex 3");
    // Touching at a vertex is meeting; running back along an edge too.
    CHECK_ONE_ERROR(plus("CLUSTER 1 POLYGON 0 0 4 0 2 2 4 4 0 4 2 2"), 5, 39, "the polygon crosses itself");
    CHECK_ONE_ERROR(plus("CLUSTER 1 POLYGON 0 0 4 0 4 2 4 1 0 3"), 5, 31, "the edge from vertex 3 to vertex 4 runs back along the edge from vertex 2 to vertex 3");
    // A vertex in the middle of a straight edge is no crossing.
    CHECK(cells_of(read_ok(plus("CLUSTER 1 POLYGON 0 0 1 0 2 0 2 2 0 2")), 1) == cells_of(read_ok(kBase), 0));
}

TEST_CASE("deck error: a POLYGON reaching outside the lattice names each vertex and edge, at the first vertex past it") {
    CHECK_ONE_ERROR(plus("CLUSTER 1 POLYGON 0 0 2 0 6 2 0 2"), 5, 27,
                    "the cluster polygon reaches outside the lattice: vertex 3 x = 6 m is past its right edge x = 4 m (the lattice is [0, 4] x [0, 4] m)");
    CHECK_ONE_ERROR(plus("CLUSTER 1 POLYGON 0 0 2 -0.5 2 2 -1 5"), 5, 25,
                    "vertex 2 y = -0.5 m is past its bottom edge y = 0 m; vertex 4 x = -1 m is past its left edge x = 0 m; vertex 4 y = 5 m is past its top edge y = 4 m");
    read_ok(plus("CLUSTER 1 POLYGON 0 0 4.0009 0 4 4"));  // a thousandth of a cell past it: inside
}

TEST_CASE("deck error: a box or POLYGON holding no cell centre names the nearest one") {
    CHECK_ONE_ERROR(plus("CLUSTER 1 0 0 0.4 4"), 5, 1, "the cluster box holds no cell centre: the nearest is (0.5, 0.5) m, 0.1 m from it");
    CHECK_ONE_ERROR(plus("CLUSTER 1 2.6 2.7 2.9 3.3"), 5, 1, "the cluster box holds no cell centre: the nearest is (2.5, 2.5) m, 0.224 m from it");
    CHECK_ONE_ERROR(plus("CLUSTER 1 1 1 1 3"), 5, 1, "the cluster box holds no cell centre: the nearest is (0.5, 1.5) m, 0.5 m from it");
    CHECK_ONE_ERROR(plus("CLUSTER 1 POLYGON 0 1.6 4 1.6 4 1.9 0 1.9"), 5, 1,
                    "the cluster polygon holds no cell centre: the nearest is (0.5, 1.5) m, 0.1 m from it");
    // A triangle between the centres (1.5, 1.5), (2.5, 1.5) and (1.5, 2.5): nearest the first.
    CHECK_ONE_ERROR(plus("CLUSTER 1 POLYGON 1.6 1.55 2.3 1.55 1.6 2.2"), 5, 1, "the nearest is (1.5, 1.5) m, 0.112 m from it");
}

// ============================================================ FILL=POINTS ===

namespace {
// The points a scene makes: (x, y, material id), in the order made.
struct Made { double x, y; int mat; };
std::vector<Made> made(const Scene& s) {
    lpfdm::Simulation sim(s);
    std::vector<Made> v;
    const lpfdm::Points& p = sim.points();
    for (std::size_t k = 0; k < p.x.size(); ++k) v.push_back({p.x[k], p.y[k], s.materials[std::size_t(sim.groups()[p.group[k]].mat_index)].id});
    return v;
}
bool same(const std::vector<Made>& a, const std::vector<Made>& b) {
    if (a.size() != b.size()) return false;
    for (std::size_t k = 0; k < a.size(); ++k)
        if (a[k].x != b[k].x || a[k].y != b[k].y || a[k].mat != b[k].mat) return false;
    return true;
}
// Even-odd: whether (x, y) lies inside the polygon v (the points tested here lie far from its edges).
bool inside(const std::vector<double>& v, double x, double y) {
    bool in = false;
    const std::size_t n = v.size() / 2;
    for (std::size_t k = 0, m = n - 1; k < n; m = k++)
        if ((v[2 * k + 1] > y) != (v[2 * m + 1] > y) && x < v[2 * k] + (y - v[2 * k + 1]) * (v[2 * m] - v[2 * k]) / (v[2 * m + 1] - v[2 * k + 1])) in = !in;
    return in;
}
}  // namespace

TEST_CASE("deck: CLUSTER ... FILL=POINTS and FILL=CELLS, on a box or a POLYGON, in any case") {
    CHECK(!read_ok(kGrid + kMaterial + "CLUSTER 1 0 0 4 4\n" + kStep).clusters[0].fill_points);
    CHECK(read_ok(kGrid + kMaterial + "CLUSTER 1 0 0 4 4 FILL=POINTS\n" + kStep).clusters[0].fill_points);
    CHECK(!read_ok(kGrid + kMaterial + "CLUSTER 1 0 0 4 4 fill=cells PPC=3\n" + kStep).clusters[0].fill_points);
    const Scene s = read_ok(kGrid + kMaterial + "CLUSTER 1 POLYGON 0 0 4 0 0 4 FILL=Points PPC=3\n" + kStep);
    CHECK(s.clusters[0].fill_points);
    CHECK(s.clusters[0].ppc == 3);
    CHECK(s.clusters[0].polygon.size() == 6);
}

TEST_CASE("deck error: FILL= takes CELLS or POINTS, once") {
    CHECK_ONE_ERROR(plus("CLUSTER 1 0 0 4 4 FILL=EDGES"), 5, 24, "unknown FILL 'EDGES' (CELLS or POINTS)");
    CHECK_ONE_ERROR(plus("CLUSTER 1 0 0 4 4 FILL=POINT"), 5, 24, "unknown FILL 'POINT' (CELLS or POINTS) (did you mean POINTS?)");
    CHECK_ONE_ERROR(plus("CLUSTER 1 0 0 4 4 FILL="), 5, 23, "missing value after FILL=");
    CHECK_ONE_ERROR(plus("CLUSTER 1 0 0 4 4 FILL=POINTS FILL=CELLS"), 5, 31, "parameter FILL given twice");
    CHECK_ONE_ERROR(plus("CLUSTER 1 0 0 4 4 FIL=POINTS"), 5, 19, "unknown parameter 'FIL' (this card takes PPC, FILL) (did you mean FILL?)");
    CHECK_ONE_ERROR(plus("CLUSTER 1 POLYGON 0 0 4 0 4 x FILL=POINTS"), 5, 29, "vertex 3 y: expected a number, found 'x'");
    // a parameter: after the fields, and the card's first problem is the one reported
    CHECK_ONE_ERROR(plus("CLUSTER 1 0 0 FILL=POINTS 4 4"), 5, 15, "FILL= stands before the field '4': the parameters (PPC=, FILL=) come after the fields");
    CHECK_ONE_ERROR(plus("CLUSTER 1 POLYGON 0 0 FILL=POINTS 4 0 0 4 PPC=3"), 5, 23, "FILL= stands before the field '4'");
    CHECK_ONE_ERROR(plus("CLUSTER 1 0 0 4 x FILL=POINT"), 5, 17, "y1: expected a number, found 'x'");
    CHECK_ONE_ERROR(plus("CLUSTER 1 0 0 4 4 FILL=POINT PPC=0"), 5, 24, "unknown FILL 'POINT'");
    CHECK_ONE_ERROR(plus("CLUSTER 1 0 0 4 4 PPC=0 FILL=POINT"), 5, 23, "PPC");
    read_ok(plus("CLUSTER 1 0 0 4 4 PPC=3 FILL=POINTS"));
    read_ok(plus("CLUSTER 1 POLYGON 0 0 4 0 &\n  0 4 FILL=POINTS &\n  PPC=3"));
    // a polygon holding no point's place: the nearest named (PPC=2: the places are L / 4 from the cells' edges)
    CHECK_ONE_ERROR(plus("CLUSTER 1 POLYGON 0 1.3 4 1.3 4 1.45 0 1.45 FILL=POINTS"), 5, 1,
                    "the cluster polygon holds no point's place (FILL=POINTS, PPC=2): the nearest is (0.25, 1.25) m, 0.05 m from it");
    read_ok(plus("CLUSTER 1 POLYGON 0 1.3 4 1.3 4 1.8 0 1.8 FILL=POINTS"));  // no cell centre, but the places at y = 1.75
}

// With one point a cell the point's place is the cell's centre: FILL=POINTS and FILL=CELLS
// make the same points. A box whose edges lie on the lattice's lines holds whole cells:
// the same points at any PPC.
TEST_CASE("deck: FILL=POINTS makes FILL=CELLS's points with PPC=1, and with a box on the lattice's lines at any PPC") {
    const char* shapes[] = {"0.25 0.25 2.75 1.75", "0.2495 0.5 1.7505 3.2", "POLYGON 0 0 4 0 4 1 1 1 1 4 0 4", "POLYGON 0.3 0.2 3.7 1.1 1.2 3.9",
                            "POLYGON 0 0 4 0 4 1.5 1.5 1.5 1.5 4 0 4"};
    for (const char* shape : shapes) {
        INFO(std::string(shape));
        const std::string card = std::string("CLUSTER 1 ") + shape + " PPC=1";
        CHECK(same(made(read_ok(kGrid + kMaterial + card + " FILL=POINTS\n" + kStep)), made(read_ok(kGrid + kMaterial + card + "\n" + kStep))));
    }
    for (const char* ppc : {"2", "3"}) {
        const std::string card = std::string("CLUSTER 1 1 0 3 4 PPC=") + ppc;
        const std::vector<Made> cells = made(read_ok(kGrid + kMaterial + card + "\n" + kStep));
        CHECK(cells.size() == std::size_t(8 * std::stoi(ppc) * std::stoi(ppc)));
        CHECK(same(made(read_ok(kGrid + kMaterial + card + " FILL=POINTS\n" + kStep)), cells));
    }
}

// A triangle whose edges pass no point's place: FILL=POINTS makes the points whose places
// lie inside it (an even-odd test written apart), each in its own cell, and their area
// differs from the triangle's by less than its perimeter times the points' spacing.
TEST_CASE("deck: FILL=POINTS makes exactly the points whose places lie inside the polygon") {
    const std::vector<double> v = {0.31, 0.17, 7.63, 1.09, 2.27, 5.71};
    const Scene s = read_ok("GRID 8 6 1\n" + kMaterial + "CLUSTER 1 POLYGON 0.31 0.17 7.63 1.09 2.27 5.71 PPC=4 FILL=POINTS\n" + kStep);
    const std::vector<Made> m = made(s);
    std::size_t expected = 0;
    for (int j = 0; j < 24; ++j)
        for (int i = 0; i < 32; ++i) expected += inside(v, (i + 0.5) / 4, (j + 0.5) / 4);
    CHECK(m.size() == expected);
    CHECK(lpfdm::count_points(s) == double(expected));
    for (const Made& p : m) CHECK(inside(v, p.x, p.y));
    const double area = 0.5 * std::fabs((v[2] - v[0]) * (v[5] - v[1]) - (v[4] - v[0]) * (v[3] - v[1]));
    const double perimeter = std::hypot(v[2] - v[0], v[3] - v[1]) + std::hypot(v[4] - v[2], v[5] - v[3]) + std::hypot(v[0] - v[4], v[1] - v[5]);
    MESSAGE("triangle of area " << area << " m^2: " << m.size() << " points of 1/16 m^2 (" << m.size() / 16.0 << " m^2)");
    CHECK(std::fabs(m.size() / 16.0 - area) < perimeter * 0.25);
    const Scene cells = read_ok("GRID 8 6 1\n" + kMaterial + "CLUSTER 1 POLYGON 0.31 0.17 7.63 1.09 2.27 5.71 PPC=4\n" + kStep);
    CHECK(std::fabs(m.size() / 16.0 - area) < std::fabs(made(cells).size() / 16.0 - area));  // (the cells' staircase errs more here)
}

// A later cluster replaces an earlier one at the places it holds: two FILL=POINTS
// triangles halving a box, of one PPC, make the box's points, each once, each of the
// material of the triangle holding it (the diagonal's points: the later one's); a
// FILL=POINTS polygon over a FILL=CELLS box keeps the box's points outside it; one of
// another PPC replaces the box's points inside it, and only those.
TEST_CASE("deck: a later FILL=POINTS cluster replaces an earlier one at the places it holds") {
    const std::string mats = "MATERIAL 1 ELASTIC E=5E7 NU=0.3 RHO=2000\nMATERIAL 2 ELASTIC E=5E7 NU=0.3 RHO=1000\n";
    const std::string grid = "GRID 8 8 0.5\n";
    const std::vector<Made> box = made(read_ok(grid + mats + "CLUSTER 1 0 0 4 4 PPC=3\n" + kStep));
    std::vector<Made> halves =
        made(read_ok(grid + mats + "CLUSTER 1 POLYGON 0 0 4 0 4 4 PPC=3 FILL=POINTS\nCLUSTER 2 POLYGON 0 0 4 4 0 4 PPC=3 FILL=POINTS\n" + kStep));
    REQUIRE(halves.size() == box.size());
    // (in a cell the first cluster's points come first: the box's order, cluster by cluster)
    std::sort(halves.begin(), halves.end(), [](const Made& a, const Made& b) {  // (places differ: a total order)
        const int ca = int(a.y / 0.5) * 8 + int(a.x / 0.5), cb = int(b.y / 0.5) * 8 + int(b.x / 0.5);
        return ca != cb ? ca < cb : a.y != b.y ? a.y < b.y : a.x < b.x;
    });
    for (std::size_t k = 0; k < box.size(); ++k) {
        CHECK(halves[k].x == box[k].x);
        CHECK(halves[k].y == box[k].y);
        CHECK(halves[k].mat == (halves[k].y >= halves[k].x ? 2 : 1));
    }
    const std::vector<double> tri = {0.3, 0.2, 3.7, 1.1, 1.2, 3.9};
    for (const char* ppc : {"3", "2"}) {
        INFO("PPC=" << std::string(ppc));
        const std::vector<Made> over = made(read_ok(grid + mats + "CLUSTER 1 0 0 4 4 PPC=3\nCLUSTER 2 POLYGON 0.3 0.2 3.7 1.1 1.2 3.9 FILL=POINTS PPC=" + ppc + "\n" + kStep));
        std::size_t kept = 0, replaced = 0;
        for (const Made& p : box) (inside(tri, p.x, p.y) ? replaced : kept) += 1;
        std::size_t ones = 0, twos = 0;
        for (const Made& p : over) {
            CHECK(inside(tri, p.x, p.y) == (p.mat == 2));
            (p.mat == 1 ? ones : twos) += 1;
        }
        CHECK(ones == kept);
        const int n = std::stoi(ppc);  // the triangle's own: its places inside it
        std::size_t own = 0;
        for (int j = 0; j < 8 * n; ++j)
            for (int i = 0; i < 8 * n; ++i) own += inside(tri, (i + 0.5) * 0.5 / n, (j + 0.5) * 0.5 / n);
        CHECK(twos == own);
        if (n == 3) CHECK(twos == replaced);
    }
}

TEST_CASE("apply_setting: CLUSTERn.PPC and .MAT on a POLYGON; its corners are not a box's") {
    lpfdm::Scene s = read_ok(plus("CLUSTER 1 POLYGON 0 0 4 0 0 4"));
    CHECK(lpfdm::apply_setting(s, "CLUSTER2.PPC", 3).empty());
    CHECK(s.clusters[1].ppc == 3);
    CHECK(lpfdm::apply_setting(s, "CLUSTER2.MAT", 1).empty());
    CHECK(lpfdm::apply_setting(s, "CLUSTER2.X0", 1) ==
          "CLUSTER 2 is a POLYGON: X0 is a box's corner, and --set cannot move a polygon's vertices (it takes MAT, PPC)");
    CHECK(lpfdm::apply_setting(s, "CLUSTER2.Y1", 1).find("is a POLYGON") != std::string::npos);
    CHECK(lpfdm::apply_setting(s, "CLUSTER2.FILL", 1) == "CLUSTER 2's FILL is a word (CELLS or POINTS), and --set takes numbers: write it on the card (--set takes MAT, PPC)");
    CHECK(lpfdm::apply_setting(s, "CLUSTER1.FILL", 1).find("(--set takes MAT, X0, Y0, X1, Y1, PPC)") != std::string::npos);  // the box
    CHECK(lpfdm::apply_setting(s, "CLUSTER1.Y1", 3).empty());  // the box beside it
    CHECK(s.clusters[0].box.y1 == 3);
    CHECK(lpfdm::validate(s).empty());
}

TEST_CASE("deck: FIX X, Y and XY hold the nodes of a box in that direction") {
    const Scene s = read_ok(kBase + "FIX X 0 0 0 4\nFIX Y 4 0 4 4\nFIX XY 0 0 4 0\nFIX YX 0 4 4 4\n");
    REQUIRE(s.fixes.size() == 4);
    CHECK(s.fixes[0].dirs == lpfdm::kFixX);
    CHECK(s.fixes[1].dirs == lpfdm::kFixY);
    CHECK(s.fixes[2].dirs == (lpfdm::kFixX | lpfdm::kFixY));
    CHECK(s.fixes[3].dirs == (lpfdm::kFixX | lpfdm::kFixY));
    CHECK(s.fixes[1].box.x0 == 4);
    CHECK(s.fixes[1].box.y1 == 4);
    CHECK(s.fixes[2].pos.line == 7);
}

TEST_CASE("deck: WALL takes an id, a box and a velocity") {
    const Scene s = read_ok(plus("WALL 3 4 1 4 3 -0.5 0.25"));
    REQUIRE(s.walls.size() == 1);
    const lpfdm::Wall& w = s.walls[0];
    CHECK(w.id == 3);
    CHECK(w.box.x0 == 4);
    CHECK(w.box.y0 == 1);
    CHECK(w.box.x1 == 4);
    CHECK(w.box.y1 == 3);
    CHECK(w.vx == -0.5);
    CHECK(w.vy == 0.25);
    CHECK(w.pos.line == 5);
}

TEST_CASE("deck: GRAVITY, DAMPING, SEED and STEP") {
    const Scene s = read_ok(kGrid + kMaterial + kCluster + "GRAVITY 0.5 -9.81\nDAMPING 0.8\nSEED 42\nSTEP 2.5E-4 600\n");
    CHECK(s.gravity_x == 0.5);
    CHECK(s.gravity_y == -9.81);
    CHECK(s.damping == 0.8);
    CHECK(s.seed == 42);
    CHECK(s.dt_s == 2.5e-4);
    CHECK(s.steps == 600);
    CHECK(s.step_pos.line == 7);
    CHECK(s.damping_pos.line == 5);
}

TEST_CASE("deck: without GRAVITY, DAMPING and SEED: no gravity, no damping, seed 1") {
    const Scene s = read_ok(kBase);
    CHECK(s.gravity_x == 0);
    CHECK(s.gravity_y == 0);
    CHECK(s.damping == 0);
    CHECK(s.seed == 1);
}

TEST_CASE("deck: OUTPUT POINTS and HISTORY, with and without EVERY") {
    const Scene s = read_ok(kBase +
                            "OUTPUT POINTS  heap_points.txt\n"
                            "OUTPUT POINTS  heap_frames.txt EVERY 5\n"
                            "OUTPUT HISTORY heap_history.txt\n"
                            "OUTPUT HISTORY heap_walls.txt EVERY 2\n");
    REQUIRE(s.outputs.size() == 4);
    CHECK(s.outputs[0].kind == lpfdm::Output::Points);
    CHECK(s.outputs[0].file == "heap_points.txt");
    CHECK(s.outputs[0].every == 0);  // first and last frame only
    CHECK(s.outputs[1].kind == lpfdm::Output::Points);
    CHECK(s.outputs[1].file == "heap_frames.txt");
    CHECK(s.outputs[1].every == 5);
    CHECK(s.outputs[2].kind == lpfdm::Output::History);
    CHECK(s.outputs[2].file == "heap_history.txt");
    CHECK(s.outputs[2].every == 0);  // every step
    CHECK(s.outputs[3].kind == lpfdm::Output::History);
    CHECK(s.outputs[3].every == 2);
    CHECK(s.outputs[3].pos.line == 8);
}

TEST_CASE("deck: a points table may have EVERY above the steps (first and last frame only)") {
    CHECK(read_ok(plus("OUTPUT POINTS p.txt EVERY 50")).outputs.at(0).every == 50);
}

TEST_CASE("deck: END ends the deck; the cards after it are not read") {
    const Scene s = read_ok(kBase +
                            "END\n"
                            "GRID 0 0 0\n"
                            "FOO bar\n"
                            "MATERIAL 9 ELASTIC E=-1\n"
                            "These are notes, not cards: 3 m of sand, E = 50 MPa.\n");
    CHECK(s.end_pos.line == 5);
    CHECK(s.end_pos.col == 1);
    CHECK(s.mx == 4);
    CHECK(s.materials.size() == 1);
}

TEST_CASE("deck: the usual cards of a scene, read into the scene's fields") {
    const Scene s = read_ok(
        "TITLE  Sand heap pushed by a wall\n"
        "GRID   40 24 0.5\n"
        "MATERIAL 1 ELASTIC E=2E7 NU=0.25 RHO=2000\n"
        "MATERIAL 2 MOHR E=5E7 NU=0.3 RHO=1900 PHI=35 C=1E3 PSI=5 TENSION=500 SOFTEN=0.5 SCATTER=0.2\n"
        "CLUSTER 1 0 0 20 2\n"
        "CLUSTER 2 0 2 10 8 PPC=3\n"
        "CLUSTER 2 POLYGON 10 2 14 2 &\n"
        "  10 6 PPC=3\n"
        "FIX X  0 0 0 12\n"
        "FIX Y  20 0 20 12\n"
        "FIX XY 0 0 20 0\n"
        "WALL 1 15 1 15 11 -0.1 0\n"
        "GRAVITY 0 -9.81\n"
        "DAMPING 0.8\n"
        "SEED 42\n"
        "STEP 1E-4 500\n"
        "OUTPUT POINTS  heap_points.txt EVERY 100\n"
        "OUTPUT HISTORY heap_history.txt EVERY 10\n"
        "END\n");
    CHECK(s.title == "Sand heap pushed by a wall");
    CHECK(s.materials.size() == 2);
    CHECK(s.clusters.size() == 3);
    CHECK(s.clusters[2].polygon.size() == 6);
    CHECK(s.fixes.size() == 3);
    CHECK(s.walls.size() == 1);
    CHECK(s.outputs.size() == 2);
    CHECK(s.end_pos.line == 19);
}

// tests/decks/good_every_card.deck, which check_decks.sh and check_cli.sh run, is meant
// to hold every card the reader knows: a card added to the language and not to it fails.
TEST_CASE("deck: tests/decks/good_every_card.deck holds every card of the deck language") {
    std::ifstream in("tests/decks/good_every_card.deck");
    REQUIRE(in);
    std::vector<std::string> first;  // each line's first word, upper case
    for (std::string line; std::getline(in, line);) {
        std::istringstream words(line);
        std::string w;
        if (!(words >> w)) continue;
        std::transform(w.begin(), w.end(), w.begin(), [](unsigned char c) { return char(std::toupper(c)); });
        first.push_back(w);
    }
    for (const std::string& card : lpfdm::card_names()) {
        INFO("card " << card);
        CHECK(std::find(first.begin(), first.end(), card) != first.end());
    }
    Scene s;
    CHECK(lpfdm::read_deck("tests/decks/good_every_card.deck", s).empty());
}

// ======================================================= lexical rules ===

TEST_CASE("deck: keywords, parameter names and choices in any case") {
    const Scene s = read_ok(
        "title Mixed Case\n"
        "grid 4 4 1\n"
        "Material 1 elastic e=5E7 Nu=0.3 rHo=2000\n"
        "material 2 Mohr e=5E7 nu=0.3 rho=2000 phi=30 c=1 psi=2 tension=3 soften=0.1 scatter=0.1\n"
        "cluster 1 0 0 2 2 ppc=3\n"
        "fix xy 0 0 4 0\n"
        "Fix x 0 0 0 4\n"
        "wall 1 4 1 4 3 -1 0\n"
        "gravity 0 -9.81\n"
        "damping 0.5\n"
        "seed 3\n"
        "step 1E-4 10\n"
        "output points p.txt every 5\n"
        "Output History h.txt Every 2\n"
        "end\n"
        "FOO\n");
    CHECK(s.title == "Mixed Case");
    REQUIRE(s.materials.size() == 2);
    CHECK(s.materials[0].nu == 0.3);
    CHECK(s.materials[1].model == lpfdm::Model::MohrCoulomb);
    CHECK(s.materials[1].scatter == 0.1);
    CHECK(s.clusters.at(0).ppc == 3);
    CHECK(s.fixes.at(0).dirs == (lpfdm::kFixX | lpfdm::kFixY));
    CHECK(s.fixes.at(1).dirs == lpfdm::kFixX);
    CHECK(s.outputs.at(1).kind == lpfdm::Output::History);
    CHECK(s.outputs.at(1).every == 2);
    CHECK(s.end_pos.line == 15);
}

TEST_CASE("deck: file names keep their case") {
    CHECK(read_ok(plus("output points Heap_Points.TXT")).outputs.at(0).file == "Heap_Points.TXT");
}

TEST_CASE("deck: fields are separated by blanks, tabs or commas") {
    const Scene s = read_ok(
        "GRID 4,4,1\n"
        "MATERIAL,1,ELASTIC,E=5E7,NU=0.3,RHO=2000\n"
        "CLUSTER\t1\t0 , 0 ,2,\t2\n"
        "  STEP   1E-4    10   \n");
    CHECK(s.mx == 4);
    CHECK(s.cell_m == 1);
    CHECK(s.materials.at(0).rho == 2000);
    CHECK(s.clusters.at(0).box.x1 == 2);
    CHECK(s.steps == 10);
}

TEST_CASE("deck: ! starts a comment anywhere on a line") {
    const Scene s = read_ok(
        "! a whole line of comment\n"
        "GRID 4 4 1 ! 8 8 0.5 was too slow\n"
        "   ! indented comment\n"
        "MATERIAL 1 ELASTIC E=5E7 NU=0.3 RHO=2000! RHO=1\n"
        "CLUSTER 1 0 0 2 2!PPC=40\n"
        "STEP 1E-4 10\n");
    CHECK(s.mx == 4);
    CHECK(s.materials.at(0).rho == 2000);
    CHECK(s.clusters.at(0).ppc == 2);
}

TEST_CASE("deck: * in column 1 makes a comment card") {
    const Scene s = read_ok(
        "* Sand heap. The next line is a comment too:\n"
        "*GRID 0 0 0\n"
        "*\n" + kBase);
    CHECK(s.mx == 4);
}

TEST_CASE("deck: * elsewhere than column 1 is an ordinary field") {
    CHECK_ONE_ERROR(" * not a comment\n" + kBase, 1, 2, "unknown card '*'");
    CHECK_ONE_ERROR(plus("GRAVITY 0 -9.81 *"), 5, 17, "extra field '*'");
}

TEST_CASE("deck: & as the last field continues the card on the next line") {
    const Scene s = read_ok(
        "GRID 4 &\n"
        "     4 1\n"
        "MATERIAL 2 MOHR E=5E7 NU=0.3 RHO=2000 &  ! elastic part\n"
        "           PHI=30 &\n"
        "           C=1E3\n"
        "CLUSTER 2 0 0 2 2 &\n"
        "  PPC=3\n"
        "STEP 1E-4 10\n");
    CHECK(s.mx == 4);
    CHECK(s.my == 4);
    CHECK(s.cell_m == 1);
    REQUIRE(s.materials.size() == 1);
    CHECK(s.materials[0].phi_deg == 30);
    CHECK(s.materials[0].c == 1e3);
    CHECK(s.clusters.at(0).ppc == 3);
    CHECK(s.steps == 10);
}

TEST_CASE("deck: & continues a card across comment cards") {
    const Scene s = read_ok(
        "GRID 4 4 &\n"
        "* the cell side in metres:\n"
        "*\n"
        "  1\n" + kMaterial + kCluster + kStep);
    CHECK(s.cell_m == 1);
}

TEST_CASE("deck: & inside a comment continues nothing") {
    CHECK(read_ok("GRID 4 4 1 ! see below &\n" + kMaterial + kCluster + kStep).mx == 4);
}

TEST_CASE("deck: a field on a continuation line is reported on that line") {
    CHECK_ONE_ERROR("GRID 4 &\n"
                    "     4 0\n" + kMaterial + kCluster + kStep,
                    2, 8, "cell size L must be > 0");
    // A missing field is reported just after the last field of the card.
    CHECK_ONE_ERROR("GRID 4 &\n"
                    "  4\n" + kMaterial + kCluster + kStep,
                    2, 4, "missing field: L");
}

TEST_CASE("deck: Fortran real numbers") {
    struct Case {
        const char* text;
        double value;
    };
    const Case cases[] = {
        {"5E7", 5e7},    {"5.0D+07", 5e7}, {"5d7", 5e7},     {"5e+7", 5e7},   {"5.E7", 5e7},  {"50E-01", 5.0},
        {"2.5D-3", 2.5e-3}, {".5", 0.5},   {"3.", 3.0},      {"-2", -2.0},    {"+3", 3.0},    {"-.5", -0.5},
        {"+.25E1", 2.5}, {"0", 0.0},       {"-9.81", -9.81}, {"007", 7.0},    {"1E-310", 1e-310},
    };
    for (const Case& c : cases) {
        INFO("c.text := " << std::string(c.text));
        const Scene s = read_ok(plus(std::string("GRAVITY 0 ") + c.text));
        CHECK(s.gravity_y == c.value);
    }
}

TEST_CASE("deck: tokens that are not Fortran reals") {
    const char* bad[] = {"1.5.2", "e5", "E5", "5E", "5E+", "1d", ".", "-", "+-3", "0x10", "1_000", "5..", "five", "5m", "5E7.0", "--1"};
    for (const char* t : bad) {
        INFO("t := " << std::string(t));
        const std::string card = std::string("GRAVITY 0 ") + t;
        Scene s;
        const Diagnostics d = read_text(plus(card), s);
        INFO(listing(d));
        REQUIRE(d.size() == 1);
        CHECK(d[0].pos.line == 5);
        CHECK(d[0].pos.col == 11);
        CHECK(has(d[0].message, std::string("gy (m/s^2): expected a number, found '") + t + "'"));
    }
}

TEST_CASE("deck: NAME=VALUE, NAME = VALUE, NAME= VALUE and NAME =VALUE read alike") {
    const Scene s = read_ok(plus("MATERIAL 2 MOHR E=5E7 NU = 0.3 RHO= 1900 PHI =30 C\t=\t1E3, PSI=5"));
    REQUIRE(s.materials.size() == 2);
    const lpfdm::Material& m = s.materials[1];
    CHECK(m.E == 5e7);
    CHECK(m.nu == 0.3);
    CHECK(m.rho == 1900);
    CHECK(m.phi_deg == 30);
    CHECK(m.c == 1e3);
    CHECK(m.psi_deg == 5);
    CHECK(read_ok(kGrid + kMaterial + "CLUSTER 1 0 0 2 2 PPC = 4\n" + kStep).clusters.at(0).ppc == 4);
}

TEST_CASE("deck: CRLF line endings read like LF") {
    const Scene s = read_ok(
        "* a deck saved on Windows\r\n"
        "TITLE Heap\r\n"
        "GRID 4 4 1\r\n"
        "MATERIAL 1 ELASTIC E=5E7 NU=0.3 RHO=2000\r\n"
        "CLUSTER 1 0 0 2 2 &\r\n"
        "  PPC=3\r\n"
        "STEP 1E-4 10\r\n"
        "OUTPUT POINTS p.txt\r\n"
        "END\r\n");
    CHECK(s.title == "Heap");
    CHECK(s.clusters.at(0).ppc == 3);
    CHECK(s.outputs.at(0).file == "p.txt");
    // The carriage return is no part of the positions.
    CHECK_ONE_ERROR("GRID 4 4\r\n" + kMaterial + kCluster + kStep, 1, 9, "missing field: L");
    CHECK_ONE_ERROR("GRID 4 4 1 9\r\n" + kMaterial + kCluster + kStep, 1, 12, "extra field '9'");
}

TEST_CASE("deck: a deck without a final newline") {
    CHECK(read_ok(kGrid + kMaterial + kCluster + "STEP 1E-4 10").steps == 10);
}

TEST_CASE("deck: whole-number fields may be written as reals") {
    const Scene s = read_ok("GRID 4.0 4E0 1\n" + kMaterial + kCluster + "STEP 1E-4 1.0D1\n");
    CHECK(s.mx == 4);
    CHECK(s.my == 4);
    CHECK(s.steps == 10);
}

// =============================================================== errors ===

TEST_CASE("deck error: unknown card") {
    CHECK_ONE_ERROR(plus("FOO 1 2"), 5, 1, "unknown card 'FOO'");
    CHECK_ONE_ERROR(plus("   grav 0 -9.81"), 5, 4, "unknown card 'grav'");
}

TEST_CASE("deck error: unknown parameter, named with the ones the card takes") {
    CHECK_ONE_ERROR(plus("MATERIAL 2 ELASTIC E=5E7 NU=0.3 RHO=2000 PHI=30"), 5, 42, "unknown parameter 'PHI' (this card takes E, NU, RHO, POROSITY, PERM)");
    CHECK_ONE_ERROR(plus("CLUSTER 1 2 2 4 4 PCC=3"), 5, 19, "unknown parameter 'PCC'");
    CHECK_ONE_ERROR(plus("MATERIAL 2 MOHR E=5E7 NU=0.3 RHO=2000 PHI=30 C=0 DILATION=5"), 5, 50, "unknown parameter 'DILATION'");
}

TEST_CASE("deck error: missing field, reported where it should have been") {
    CHECK_ONE_ERROR("GRID 4 4\n" + kMaterial + kCluster + kStep, 1, 9, "missing field: L (cell size, m)");
    CHECK_ONE_ERROR("GRID\n" + kMaterial + kCluster + kStep, 1, 5, "missing field: mx");
    CHECK_ONE_ERROR(plus("FIX X 0 0 4"), 5, 12, "missing field: y1");
    CHECK_ONE_ERROR(plus("WALL 1 4 0 4 4 -0.1"), 5, 20, "missing field: VY");
    CHECK_ONE_ERROR(plus("GRAVITY -9.81"), 5, 14, "missing field: gy");
    CHECK_ONE_ERROR(plus("GRAVITY=0 -9.81"), 5, 8, "missing field: gx");
    CHECK_ONE_ERROR(plus("MATERIAL 2"), 5, 11, "missing field: model");
    CHECK_ONE_ERROR(plus("OUTPUT POINTS"), 5, 14, "missing field: file name");
    CHECK_ONE_ERROR(plus("OUTPUT"), 5, 7, "missing field: kind");
    CHECK_ONE_ERROR(plus("OUTPUT HISTORY h.txt EVERY"), 5, 27, "missing field: EVERY n");
    CHECK_ONE_ERROR(kGrid + kMaterial + kCluster + "STEP 1E-4\n", 4, 10, "missing field: number of steps");
    // A parameter where a positional field belongs.
    CHECK_ONE_ERROR(plus("CLUSTER 1 2 2 4 PPC=2"), 5, 17, "missing field: y1");
    // "ELASTIC =5E7" reads as the parameter ELASTIC=5E7: the model is missing.
    CHECK_ONE_ERROR(plus("MATERIAL 2 ELASTIC =5E7 NU=0.3 RHO=2000"), 5, 12, "missing field: model");
}

TEST_CASE("deck error: missing parameter or parameter value") {
    CHECK_ONE_ERROR(plus("MATERIAL 2 ELASTIC E=5E7 NU=0.3"), 5, 32, "missing parameter RHO=");
    CHECK_ONE_ERROR(plus("MATERIAL 2 ELASTIC"), 5, 19, "missing parameter E=");
    CHECK_ONE_ERROR(plus("MATERIAL 2 MOHR E=5E7 NU=0.3 RHO=2000 PHI=30"), 5, 45, "missing parameter C=");
    CHECK_ONE_ERROR(plus("MATERIAL 2 ELASTIC NU=0.3 RHO=2000 E="), 5, 37, "missing value after E=");
    CHECK_ONE_ERROR(plus("MATERIAL 2 ELASTIC E=5E7 = NU=0.3 RHO=2000"), 5, 26, "'=' without a parameter name");
    CHECK_ONE_ERROR(plus("MATERIAL 2 ELASTIC E= NU=0.3 RHO=2000"), 5, 23, "E: expected a number, found 'NU'");
}

TEST_CASE("deck error: extra field") {
    CHECK_ONE_ERROR("GRID 4 4 1 9\n" + kMaterial + kCluster + kStep, 1, 12, "extra field '9'");
    CHECK_ONE_ERROR(plus("GRAVITY 0 -9.81 0"), 5, 17, "extra field '0'");
    CHECK_ONE_ERROR(plus("SEED 1 2"), 5, 8, "extra field '2'");
    CHECK_ONE_ERROR(plus("MATERIAL 2 ELASTIC E=5E7 NU=0.3 RHO=2000 7"), 5, 42, "extra field '7'");
    CHECK_ONE_ERROR(plus("MATERIAL 2 ELASTIC E 5E7 NU=0.3 RHO=2000"), 5, 20, "extra field 'E'");
    CHECK_ONE_ERROR(plus("OUTPUT POINTS p.txt EVERY 5 6"), 5, 29, "extra field '6'");
    CHECK_ONE_ERROR(plus("OUTPUT POINTS p.txt 5"), 5, 21, "extra field '5'");
    CHECK_ONE_ERROR(kBase + "END now\n", 5, 5, "extra field 'now'");
    CHECK_ONE_ERROR("TITLE Heap\n" + kGrid + kMaterial + kCluster + kStep + "DAMPING 0.5 0.5\n", 6, 13, "extra field '0.5'");
}

TEST_CASE("deck error: a field that is not a number") {
    CHECK_ONE_ERROR("GRID 4 four 1\n" + kMaterial + kCluster + kStep, 1, 8, "expected a number, found 'four'");
    CHECK_ONE_ERROR(plus("MATERIAL 2 ELASTIC E=5E7x NU=0.3 RHO=2000"), 5, 22, "E: expected a number, found '5E7x'");
    CHECK_ONE_ERROR(plus("GRAVITY 0 g"), 5, 11, "expected a number, found 'g'");
    CHECK_ONE_ERROR(plus("WALL 1 4 0 4 4 slow 0"), 5, 16, "expected a number, found 'slow'");
    CHECK_ONE_ERROR(plus("CLUSTER one 2 2 4 4"), 5, 9, "expected a number, found 'one'");
}

TEST_CASE("deck error: nan and inf are not numbers of a deck") {
    CHECK_ONE_ERROR(plus("MATERIAL 2 ELASTIC E=5E7 NU=nan RHO=2000"), 5, 29, "'nan' is not a finite number");
    CHECK_ONE_ERROR(plus("MATERIAL 2 ELASTIC E=NaN NU=0.3 RHO=2000"), 5, 22, "'NaN' is not a finite number");
    CHECK_ONE_ERROR(plus("GRAVITY 0 -inf"), 5, 11, "'-inf' is not a finite number");
    CHECK_ONE_ERROR(plus("DAMPING Infinity"), 5, 9, "'Infinity' is not a finite number");
    CHECK_ONE_ERROR("GRID INF 4 1\n" + kMaterial + kCluster + kStep, 1, 6, "'INF' is not a finite number");
    CHECK_ONE_ERROR(plus("WALL 1 4 0 4 4 +inf 0"), 5, 16, "'+inf' is not a finite number");
}

TEST_CASE("deck error: cells and cell size must be > 0") {
    CHECK_ONE_ERROR("GRID 0 4 1\n" + kMaterial + kCluster + kStep, 1, 6, "mx (cells in x) must lie in [1, 1000000], found '0'");
    CHECK_ONE_ERROR("GRID 4 -2 1\n" + kMaterial + kCluster + kStep, 1, 8, "my (cells in y) must lie in [1, 1000000], found '-2'");
    CHECK_ONE_ERROR("GRID 4 4 0\n" + kMaterial + kCluster + kStep, 1, 10, "the cell size L must be > 0");
    CHECK_ONE_ERROR("GRID 4 4 -0.5\n" + kMaterial + kCluster + kStep, 1, 10, "the cell size L must be > 0");
    CHECK_ONE_ERROR("GRID 4.5 4 1\n" + kMaterial + kCluster + kStep, 1, 6, "mx (cells in x) must be a whole number, found '4.5'");
    CHECK_ONE_ERROR("GRID 2000000 4 1\n" + kMaterial + kCluster + kStep, 1, 6, "must lie in [1, 1000000]");
}

TEST_CASE("deck error: E <= 0, RHO <= 0, NU outside (-1, 0.5): at the value") {
    CHECK_ONE_ERROR(plus("MATERIAL 2 ELASTIC E=0 NU=0.3 RHO=2000"), 5, 22, "E must be > 0");
    CHECK_ONE_ERROR(plus("MATERIAL 2 ELASTIC E=-5E7 NU=0.3 RHO=2000"), 5, 22, "E must be > 0");
    CHECK_ONE_ERROR(plus("MATERIAL 2 ELASTIC E=5E7 NU=0.3 RHO=0"), 5, 37, "RHO must be > 0");
    CHECK_ONE_ERROR(plus("MATERIAL 2 ELASTIC E=5E7 NU=0.3 RHO=-2000"), 5, 37, "RHO must be > 0");
    CHECK_ONE_ERROR(plus("MATERIAL 2 ELASTIC E=5E7 NU=0.5 RHO=2000"), 5, 29, "NU must lie in (-1, 0.5)");
    CHECK_ONE_ERROR(plus("MATERIAL 2 ELASTIC E=5E7 NU=-1 RHO=2000"), 5, 29, "NU must lie in (-1, 0.5)");
    CHECK_ONE_ERROR(plus("MATERIAL 2 MOHR E=5E7 NU=0.7 RHO=2000 PHI=30 C=0"), 5, 26, "NU must lie in (-1, 0.5)");
    // Just inside the bounds is fine.
    read_ok(plus("MATERIAL 2 ELASTIC E=1E-3 NU=-0.99 RHO=1E-3"));
    read_ok(plus("MATERIAL 2 ELASTIC E=5E7 NU=0.49 RHO=2000"));
}

TEST_CASE("deck error: material id outside [1, 65535]") {
    CHECK_ONE_ERROR(plus("MATERIAL 0 ELASTIC E=5E7 NU=0.3 RHO=2000"), 5, 10, "material id must lie in [1, 65535], found '0'");
    CHECK_ONE_ERROR(plus("MATERIAL 1.5 ELASTIC E=5E7 NU=0.3 RHO=2000"), 5, 10, "material id must be a whole number");
}

TEST_CASE("deck error: MOHR parameters out of range: at the value") {
    const std::string mohr = "MATERIAL 2 MOHR E=5E7 NU=0.3 RHO=2000 ";  // 38 columns
    CHECK_ONE_ERROR(plus(mohr + "PHI=90 C=1E3"), 5, 43, "PHI must lie in [0, 90) degrees");
    CHECK_ONE_ERROR(plus(mohr + "PHI=-1 C=1E3"), 5, 43, "PHI must lie in [0, 90) degrees");
    CHECK_ONE_ERROR(plus(mohr + "PHI=30 C=1E3 PSI=31"), 5, 56, "PSI must lie in [0, PHI]");
    CHECK_ONE_ERROR(plus(mohr + "PHI=30 C=1E3 PSI=-1"), 5, 56, "PSI must lie in [0, PHI]");
    CHECK_ONE_ERROR(plus(mohr + "PHI=30 C=-1"), 5, 48, "C must be >= 0");
    CHECK_ONE_ERROR(plus(mohr + "PHI=30 C=1E3 TENSION=-1"), 5, 60, "TENSION must be >= 0");
    CHECK_ONE_ERROR(plus(mohr + "PHI=30 C=1E3 SOFTEN=1.5"), 5, 59, "SOFTEN must lie in [0, 1]");
    CHECK_ONE_ERROR(plus(mohr + "PHI=30 C=1E3 SOFTEN=-0.1"), 5, 59, "SOFTEN must lie in [0, 1]");
    CHECK_ONE_ERROR(plus(mohr + "PHI=30 C=1E3 SCATTER=-0.1"), 5, 60, "SCATTER must be >= 0");
    // The bounds themselves.
    read_ok(plus(mohr + "PHI=0 C=1E3 PSI=0 TENSION=0 SOFTEN=1 SCATTER=0.5"));
    read_ok(plus(mohr + "PHI=89.9 C=0 PSI=89.9 SOFTEN=0"));
}

TEST_CASE("deck error: MOHR checks of the material as a whole, on its card") {
    const std::string mohr = "MATERIAL 2 MOHR E=5E7 NU=0.3 RHO=2000 ";
    CHECK_ONE_ERROR(plus(mohr + "PHI=30 C=1E3 SCATTER=0.6"), 5, 60, "SCATTER above 0.5");
    CHECK_ONE_ERROR(plus(mohr + "PHI=80 C=1E3 SCATTER=0.1"), 5, 1, "SCATTER too large for this PHI");
    CHECK_ONE_ERROR(plus(mohr + "PHI=0 C=0"), 5, 1, "no strength");
}

TEST_CASE("deck error: PPC below 1, not whole, or absurdly large") {
    CHECK_ONE_ERROR(plus("CLUSTER 1 2 2 4 4 PPC=0"), 5, 23, "PPC must be a whole number in [1, 32]");
    CHECK_ONE_ERROR(plus("CLUSTER 1 2 2 4 4 PPC=-3"), 5, 23, "PPC must be a whole number in [1, 32]");
    CHECK_ONE_ERROR(plus("CLUSTER 1 2 2 4 4 PPC=2.5"), 5, 23, "PPC must be a whole number in [1, 32]");
    CHECK_ONE_ERROR(plus("CLUSTER 1 2 2 4 4 PPC=33"), 5, 23, "PPC must be a whole number in [1, 32]");
    CHECK_ONE_ERROR(plus("CLUSTER 1 2 2 4 4 PPC=1E6"), 5, 23, "PPC must be a whole number in [1, 32]");
    CHECK(read_ok(plus("CLUSTER 1 2 2 4 4 PPC=32")).clusters.at(1).ppc == 32);
    CHECK(read_ok(plus("CLUSTER 1 2 2 4 4 PPC=1")).clusters.at(1).ppc == 1);
}

TEST_CASE("deck error: PPC far beyond any integer") {
    // The value must be rejected before it is converted to an integer.
    CHECK_ONE_ERROR(plus("CLUSTER 1 2 2 4 4 PPC=1E300"), 5, 23, "PPC must be a whole number in [1, 32]");
}

TEST_CASE("deck error: a cluster outside the lattice, or holding no cell centre") {
    CHECK_ONE_ERROR(plus("CLUSTER 1 2 2 4.5 4"), 5, 1, "the cluster box reaches outside the lattice");
    CHECK_ONE_ERROR(plus("CLUSTER 1 -1 0 2 2"), 5, 1, "the cluster box reaches outside the lattice");
    CHECK_ONE_ERROR(plus("CLUSTER 1 0 0 0.4 4"), 5, 1, "the cluster box holds no cell centre");
    CHECK_ONE_ERROR(plus("CLUSTER 1 1 1 1 3"), 5, 1, "the cluster box holds no cell centre");
    CHECK_ONE_ERROR(plus("CLUSTER 1 3 3 1 1"), 5, 1, "the box needs x0 <= x1 and y0 <= y1");
    // A box edge a thousandth of a cell past the lattice is still inside.
    read_ok(plus("CLUSTER 1 0 0 4.0009 4"));
}

TEST_CASE("deck error: undefined or duplicated material id") {
    CHECK_ONE_ERROR(plus("CLUSTER 3 2 2 4 4"), 5, 1, "material 3 is not defined");
    CHECK_ONE_ERROR(plus("MATERIAL 1 ELASTIC E=1E7 NU=0.2 RHO=1800"), 5, 1, "material 1 is defined twice");
    // A material may be defined after the cluster that uses it.
    read_ok(kGrid + "CLUSTER 2 0 0 2 2\nMATERIAL 2 ELASTIC E=5E7 NU=0.3 RHO=2000\n" + kStep);
}

TEST_CASE("deck error: unknown direction, material model or output kind") {
    CHECK_ONE_ERROR(plus("FIX Z 0 0 4 0"), 5, 5, "unknown direction 'Z' (X, Y or XY)");
    CHECK_ONE_ERROR(plus("FIX XZ 0 0 4 0"), 5, 5, "unknown direction 'XZ'");
    CHECK_ONE_ERROR(plus("FIX 0 0 4 0"), 5, 5, "unknown direction '0'");
    CHECK_ONE_ERROR(plus("MATERIAL 2 PLASTIC E=5E7 NU=0.3 RHO=2000"), 5, 12, "unknown material model 'PLASTIC' (ELASTIC or MOHR)");
    CHECK_ONE_ERROR(plus("OUTPUT FRAMES f.txt"), 5, 8, "unknown output 'FRAMES' (POINTS, HISTORY, VTU or STATE)");
    CHECK_ONE_ERROR(plus("OUTPUT VTK f"), 5, 8, "unknown output 'VTK' (POINTS, HISTORY, VTU or STATE) (did you mean VTU?)");
}

TEST_CASE("deck: OUTPUT VTU (ASCII or BINARY) and OUTPUT STATE") {
    const Scene s = read_ok(kBase +
                            "OUTPUT VTU heap\n"
                            "OUTPUT VTU heapb BINARY EVERY 5\n"
                            "output vtu heapc binary nodes every=7\n"
                            "OUTPUT STATE heap.state EVERY 100\n");
    REQUIRE(s.outputs.size() == 4);
    CHECK(s.outputs[0].kind == lpfdm::Output::Vtu);
    CHECK(s.outputs[0].file == "heap");
    CHECK(!s.outputs[0].binary);
    CHECK(s.outputs[0].every == 0);
    CHECK(s.outputs[1].kind == lpfdm::Output::Vtu);
    CHECK(s.outputs[1].binary);
    CHECK(s.outputs[1].every == 5);
    CHECK(s.outputs[2].binary);
    CHECK(s.outputs[2].nodes);
    CHECK(!s.outputs[1].nodes);
    CHECK(s.outputs[2].every == 7);
    CHECK(s.outputs[3].kind == lpfdm::Output::State);
    CHECK(s.outputs[3].file == "heap.state");
    CHECK(s.outputs[3].every == 100);
    CHECK_ONE_ERROR(plus("OUTPUT POINTS p.txt BINARY"), 5, 21, "BINARY is a word of OUTPUT VTU only");
    CHECK_ONE_ERROR(plus("OUTPUT STATE s BINARY EVERY 5"), 5, 16, "BINARY is a word of OUTPUT VTU only");
    CHECK_ONE_ERROR(plus("OUTPUT VTU v EVERY 5 BINARY"), 5, 22, "extra field 'BINARY'");
    CHECK_ONE_ERROR(plus("OUTPUT VTU v NODES BINARY NODES"), 5, 27, "NODES given twice");
    CHECK_ONE_ERROR(plus("OUTPUT HISTORY h.txt NODES"), 5, 22, "NODES is a word of OUTPUT VTU only");
}

TEST_CASE("deck error: a FIX box that holds no node") {
    CHECK_ONE_ERROR(plus("FIX X 0.2 0.2 0.8 0.8"), 5, 1, "the FIX box holds no node");
    CHECK_ONE_ERROR(plus("FIX X 5 0 6 4"), 5, 1, "the FIX box holds no node");
    CHECK_ONE_ERROR(plus("FIX X 4 0 0 4"), 5, 1, "the box needs x0 <= x1 and y0 <= y1");
    // A degenerate box selects a line of nodes; a box may reach past the lattice.
    read_ok(plus("FIX X 3 0 3 4"));
    read_ok(plus("FIX XY -1 -1 5 0"));
}

TEST_CASE("deck error: dt <= 0 and steps < 1") {
    CHECK_ONE_ERROR(kGrid + kMaterial + kCluster + "STEP 0 10\n", 4, 6, "the time step dt must be > 0");
    CHECK_ONE_ERROR(kGrid + kMaterial + kCluster + "STEP -1E-4 10\n", 4, 6, "the time step dt must be > 0");
    CHECK_ONE_ERROR(kGrid + kMaterial + kCluster + "STEP 1E-4 0\n", 4, 11, "number of steps must lie in [1, 1000000000], found '0'");
    CHECK_ONE_ERROR(kGrid + kMaterial + kCluster + "STEP 1E-4 -5\n", 4, 11, "number of steps must lie in");
    CHECK_ONE_ERROR(kGrid + kMaterial + kCluster + "STEP 1E-4 2.5\n", 4, 11, "number of steps must be a whole number");
}

TEST_CASE("deck error: dt above the stable limit; the message gives the limit") {
    // E = 5e7 Pa, nu = 0.3, rho = 2000 kg/m^3: M = K + 4G/3 = 6.7308e7 Pa, lambda = K - 2G/3 =
    // 2.8846e7 Pa, limit L sqrt(rho / (M + lambda)) = 4.5607e-3 s (L / c_p would be 5.451e-3 s).
    CHECK_ONE_ERROR(kGrid + kMaterial + kCluster + "STEP 5E-3 10\n", 4, 1, "above the stable limit 0.0045607 s");
    read_ok(kGrid + kMaterial + kCluster + "STEP 4.56E-3 10\n");
    // Local damping lowers it by sqrt(1 + alpha): 4.5607e-3 / sqrt(1.8) = 3.3994e-3 s.
    CHECK_ONE_ERROR(kGrid + kMaterial + kCluster + "STEP 4E-3 10\nDAMPING 0.8\n", 4, 1, "above the stable limit 0.00339935 s");
    // The stiffest material decides, used by a cluster or not.
    CHECK_ONE_ERROR(kGrid + kMaterial + kCluster + "STEP 1E-3 10\nMATERIAL 2 ELASTIC E=5E9 NU=0.3 RHO=2000\n", 4, 1,
                    "above the stable limit 0.00045607 s");
}

// DAMPING WINDOW=t (damped_increment): the base scene's slowest elastic period 4 W / c_p,
// W = 4 m, c_p = sqrt(M / rho) = 183.5 m/s: 0.0872 s.
TEST_CASE("deck: DAMPING alpha WINDOW=t; a window shorter than dt is an error at the card, one shorter than the slowest elastic period a warning") {
    const Scene s = read_ok(plus("DAMPING 0.8 WINDOW=0.1"));
    CHECK(s.damping == 0.8);
    CHECK(s.damping_window == 0.1);
    CHECK(lpfdm::warnings(s).empty());
    CHECK(read_ok(plus("DAMPING 0.5")).damping_window == 0);
    // (over less than two steps the mean all but follows the increment and the damping's
    // sign about it is rounding: a window of dt pushed psc.deck until a node jumped)
    CHECK_ONE_ERROR(plus("DAMPING 0.8 WINDOW=5E-5"), 5, 1, "DAMPING WINDOW=5e-05 s is shorter than two time steps, 2 dt = 0.0002 s");
    CHECK_ONE_ERROR(plus("DAMPING 0.8 WINDOW=1E-4"), 5, 1, "DAMPING WINDOW=0.0001 s is shorter than two time steps");
    CHECK(read_ok(plus("DAMPING 0.8 WINDOW=2E-4")).damping_window == 2e-4);
    CHECK(read_ok(plus("DAMPING 0 WINDOW=5E-5")).damping_window == 5e-5);  // nothing to damp: not asked about
    CHECK_ONE_ERROR(plus("DAMPING 0.8 WINDOW=-1"), 5, 20, "WINDOW must be >= 0");
    const Diagnostics w = lpfdm::warnings(read_ok(plus("DAMPING 0.8 WINDOW=0.05")));
    INFO(listing(w));
    REQUIRE(w.size() == 1);
    CHECK(w[0].pos.line == 5);
    CHECK(has(w[0].message, "shorter than 4 W / c_p = 0.0872 s"));
    CHECK(lpfdm::warnings(read_ok(plus("DAMPING 0 WINDOW=0.05"))).empty());  // nothing to damp
    Scene a = read_ok(plus("DAMPING 0.8"));
    CHECK(lpfdm::apply_setting(a, "DAMPING.WINDOW", 0.2).empty());
    CHECK(a.damping_window == 0.2);
}

TEST_CASE("deck error: walls that select no node, set a direction another card sets at a node they share, or move too fast") {
    CHECK_ONE_ERROR(plus("WALL 1 0.2 0.2 0.8 0.8 0 0"), 5, 1, "the WALL box holds no node");
    CHECK_ONE_ERROR(plus("WALL 1 4 3 4 1 -1 0"), 5, 1, "the box needs x0 <= x1 and y0 <= y1");
    // Constraints combine where they set different directions; where both set one, both cards are named.
    CHECK_ONE_ERROR(kBase + "FIX XY 0 0 4 0\nWALL 1 4 0 4 4 -1 0\n", 6, 1, "WALL 1 and the FIX at line 5 both set x and y at the nodes they share (x = 4 m, y = 0 m)");
    CHECK_ONE_ERROR(kBase + "FIX XY 0 0 4 0\nWALL 1 4 0 4 4 -1 0 SMOOTH\n", 6, 1, "WALL 1 and the FIX at line 5 both set x at the nodes they share (x = 4 m, y = 0 m)");
    CHECK_ONE_ERROR(kBase + "FIX Y 0 0 4 0\nWALL 1 4 0 4 4 -1 0\n", 6, 1, "WALL 1 and the FIX at line 5 both set y at the nodes they share (x = 4 m, y = 0 m)");
    CHECK_ONE_ERROR(kBase + "FIX X 4 0 4 4\nWALL 1 4 2 4 4 0 0 SMOOTH\n", 6, 1, "WALL 1 and the FIX at line 5 both set x at the nodes they share (x = 4 m, y = 2 to 4 m)");
    CHECK_ONE_ERROR(kBase + "WALL 1 4 1 4 4 -1 0 SMOOTH\nWALL 2 2 4 4 4 0 -1\n", 6, 1, "WALL 2 and WALL 1 (line 5) both set x at the nodes they share (x = 4 m, y = 4 m)");
    read_ok(kBase + "FIX Y 0 0 4 0\nWALL 1 4 0 4 4 -1 0 SMOOTH\n");                       // a smooth wall's x, the base's y
    read_ok(kBase + "WALL 1 4 1 4 4 -1 0 SMOOTH\nWALL 2 2 4 4 4 0 -1 SMOOTH\n");             // a column's x, a row's y
    read_ok(kBase + "FIX X 0 0 0 4\nFIX Y 0 0 4 0\nWALL 1 0 4 4 4 0 -1 SMOOTH\n");         // a cap pressing down between smooth sides
    // 0.1 cell per step is allowed, more is not: L = 1 m, dt = 1e-4 s.
    read_ok(plus("WALL 1 4 1 4 4 -1000 0"));
    CHECK_ONE_ERROR(plus("WALL 1 4 1 4 4 -1001 0"), 5, 1, "at most 0.1 is allowed");
    CHECK_ONE_ERROR(plus("WALL 1 4 1 4 4 800 800"), 5, 1, "the wall moves 0.113 cells per step;");
    CHECK_ONE_ERROR(kBase + "WALL 1 4 1 4 4 -1 0\nWALL 1 0 1 0 4 1 0\n", 6, 1, "wall 1 is defined twice");
    CHECK_ONE_ERROR(plus("WALL 0 4 1 4 4 -1 0"), 5, 6, "wall id must lie in [1, 65535]");
}

// A run shorter than an output interval (`--steps 100` on a deck writing every 500 steps)
// runs: it writes its last row and is warned (tests/check_decks.sh runs it).
TEST_CASE("deck: a history whose EVERY exceeds the steps is warned, not refused") {
    const Scene s = read_ok(plus("OUTPUT HISTORY h.txt EVERY 11"));
    const Diagnostics w = lpfdm::warnings(s);
    INFO(listing(w));
    REQUIRE(w.size() == 1);
    CHECK(w[0].warning);
    CHECK(w[0].pos.line == 5);
    CHECK(w[0].str() == "t.deck:5:1: warning: EVERY 11 is more than the 10 steps of the run: only the last row is written");
    CHECK(lpfdm::warnings(read_ok(plus("OUTPUT HISTORY h.txt EVERY 10"))).empty());
    CHECK_ONE_ERROR(plus("OUTPUT HISTORY h.txt EVERY 0"), 5, 28, "EVERY n must lie in [1, 1000000000], found '0'");
    CHECK_ONE_ERROR(plus("OUTPUT POINTS p.txt EVERY 2.5"), 5, 27, "EVERY n must be a whole number");
}

TEST_CASE("deck error: DAMPING outside [0, 1)") {
    CHECK_ONE_ERROR(plus("DAMPING 1"), 5, 9, "DAMPING alpha must lie in [0, 1)");
    CHECK_ONE_ERROR(plus("DAMPING -0.1"), 5, 9, "DAMPING alpha must lie in [0, 1)");
    CHECK(read_ok(plus("DAMPING 0.999")).damping == 0.999);
}

TEST_CASE("deck error: SEED outside [0, 2^53]") {
    CHECK_ONE_ERROR(plus("SEED -1"), 5, 6, "seed must lie in [0, 9007199254740992]");
    CHECK_ONE_ERROR(plus("SEED 1.5"), 5, 6, "seed must be a whole number");
    CHECK(read_ok(plus("SEED 0")).seed == 0);
    CHECK(read_ok(plus("SEED 9007199254740992")).seed == 9007199254740992ull);
}

TEST_CASE("deck error: a card that may appear once, given twice") {
    CHECK_ONE_ERROR(plus("GRID 8 8 0.5"), 5, 1, "GRID is given twice");
    CHECK_ONE_ERROR(plus("STEP 1E-4 20"), 5, 1, "STEP is given twice");
    CHECK_ONE_ERROR("TITLE a\n" + kBase + "TITLE b\n", 6, 1, "TITLE is given twice");
    CHECK_ONE_ERROR(kBase + "GRAVITY 0 -9.81\ngravity 0 -10\n", 6, 1, "GRAVITY is given twice");
    CHECK_ONE_ERROR(kBase + "DAMPING 0.8\nDAMPING 0.7\n", 6, 1, "DAMPING is given twice");
    CHECK_ONE_ERROR(kBase + "SEED 1\nSEED 2\n", 6, 1, "SEED is given twice");
}

TEST_CASE("deck error: a parameter given twice") {
    CHECK_ONE_ERROR(plus("MATERIAL 2 ELASTIC E=5E7 NU=0.3 e=6E7 RHO=2000"), 5, 33, "parameter E given twice");
    CHECK_ONE_ERROR(plus("CLUSTER 1 2 2 4 4 PPC=2 PPC=3"), 5, 25, "parameter PPC given twice");
}

TEST_CASE("deck error: output files: one name per card, no directory") {
    CHECK_ONE_ERROR(kBase + "OUTPUT POINTS a.txt\nOUTPUT HISTORY a.txt\n", 6, 16, "file 'a.txt' is written by another OUTPUT card");
    CHECK_ONE_ERROR(plus("OUTPUT POINTS out/a.txt"), 5, 15, "the file name must not contain a directory");
    CHECK_ONE_ERROR(plus("OUTPUT POINTS ../a.txt"), 5, 15, "the file name must not contain a directory");
    CHECK_ONE_ERROR(plus("OUTPUT HISTORY .."), 5, 16, "the file name must not contain a directory");
}

// Once wrong: a cluster outside the lattice was told as "[0, 4.000000] x [0, 4.000000] m",
// without the edge it crosses. Each edge crossed is named, with the box's number as the
// deck writes it and the lattice's extent.
TEST_CASE("deck error: a cluster outside the lattice names each edge it crosses") {
    CHECK_ONE_ERROR(plus("CLUSTER 1 2 2 4.5 4"), 5, 1,
                    "the cluster box reaches outside the lattice: x1 = 4.5 m is past its right edge x = 4 m (the lattice is [0, 4] x [0, 4] m)");
    CHECK_ONE_ERROR(plus("CLUSTER 1 -1 0 2 2"), 5, 1, "x0 = -1 m is past its left edge x = 0 m (the lattice is [0, 4] x [0, 4] m)");
    CHECK_ONE_ERROR(plus("CLUSTER 1 0 -0.25 2 2"), 5, 1, "y0 = -0.25 m is past its bottom edge y = 0 m");
    CHECK_ONE_ERROR(plus("CLUSTER 1 0 0 2 7"), 5, 1, "y1 = 7 m is past its top edge y = 4 m");
    // Two edges in one message; 40 x 20 cells of 0.1 m: the extent as 4 and 2, not 4.000000000000001.
    CHECK_ONE_ERROR("GRID 40 20 0.1\n" + kMaterial + "CLUSTER 1 -0.5 0 2 2.5\nSTEP 1E-5 10\n", 3, 1,
                    "x0 = -0.5 m is past its left edge x = 0 m; y1 = 2.5 m is past its top edge y = 2 m (the lattice is [0, 4] x [0, 2] m)");
    Scene s;
    const Diagnostics d = read_text(plus("CLUSTER 1 0 0 6 2"), s);
    REQUIRE(d.size() == 1);
    CHECK(d[0].message.find("000000") == std::string::npos);  // no %f
}

// Once wrong: a misspelt card was followed by what it left missing ("no CLUSTER card" at
// the GRID line, before the misspelt card). A card missing from the deck is not reported
// when an unknown card is nearest to it, and the scene's checks that depend on a card
// with an error (a misspelt FIX: SHAKE's fixed nodes; a misspelt MAPPING: ADVECT FLIP's
// need of MAPPING SMOOTH) are left out.
TEST_CASE("deck error: a misspelt card is reported alone, not also the card it leaves missing") {
    CHECK_ONE_ERROR(kGrid + kMaterial + "CLUSTR 1 0 0 2 2\n" + kStep, 3, 1, "unknown card 'CLUSTR' (did you mean CLUSTER?)");
    CHECK_ONE_ERROR("GIRD 4 4 1\n" + kMaterial + kCluster + kStep, 1, 1, "unknown card 'GIRD' (did you mean GRID?)");
    CHECK_ONE_ERROR(kGrid + kMaterial + kCluster + "STPE 1E-4 10\n", 4, 1, "unknown card 'STPE' (did you mean STEP?)");
    CHECK_ONE_ERROR(kBase + "MAPING SMOOTH\nADVECT FLIP\n", 5, 1, "unknown card 'MAPING' (did you mean MAPPING?)");
    CHECK_ONE_ERROR(kBase + "MAPPING SMOTH\nADVECT FLIP\n", 5, 9, "unknown mapping 'SMOTH'");
    Scene s;
    CHECK(has(listing(read_text(kBase + "ADVECT FLIP\n", s)), "ADVECT FLIP needs MAPPING SMOOTH"));  // without the card's error
    // A misspelt FIX card, or one with an error, and a SHAKE card whose record is fine: one message.
    const std::string dir = "build/test_deck_motion";
    std::filesystem::create_directories(dir);
    std::ofstream(dir + "/m.txt") << "0 0\n0.1 1\n";
    auto shaken = [&](const std::string& fix) {
        Scene t;
        return lpfdm::read_deck_text(kBase + fix + "SHAKE X FILE=m.txt\n", dir + "/t.deck", t);
    };
    Diagnostics d = shaken("FIXX XY 0 0 4 0\n");
    INFO(listing(d));
    REQUIRE(d.size() == 1);
    CHECK(has(d[0].message, "unknown card 'FIXX' (did you mean FIX?)"));
    d = shaken("FIX Q 0 0 4 0\n");
    INFO(listing(d));
    REQUIRE(d.size() == 1);
    CHECK(has(d[0].message, "unknown direction 'Q'"));
    CHECK(has(listing(shaken("")), "no FIX card holds that direction"));  // without the FIX card's error
}

// A card near no card name may be anything: what is missing is still reported, but after
// the unknown card, at the last card.
TEST_CASE("deck error: a card missing from the deck is reported after the cards") {
    Scene s;
    const Diagnostics d = read_text(kGrid + "XYZZY 1\n" + kMaterial + kStep, s);
    INFO(listing(d));
    REQUIRE(d.size() == 2);
    CHECK(d[0].pos.line == 2);
    CHECK(has(d[0].message, "unknown card 'XYZZY'"));
    CHECK(d[1].pos.line == 4);
    CHECK(has(d[1].message, "no CLUSTER card"));
}

// Once wrong: a missing motion file was named at the end, in parentheses after the
// system's message. The message names the path tried where it names the file.
TEST_CASE("deck error: a motion file that cannot be opened is named by the path tried") {
    auto shake = [](const std::string& file, const std::string& deck) {
        Scene s;
        return listing(lpfdm::read_deck_text(kBase + "FIX XY 0 0 4 0\nSHAKE X FILE=" + file + "\n", deck, s));
    };
    CHECK(shake("nowhere.txt", "no-such-dir/t.deck") ==
          "no-such-dir/t.deck:6:14: error: cannot open the motion file 'no-such-dir/nowhere.txt': No such file or directory "
          "(a relative FILE= is read from the deck's directory)\n");
    // Beside a deck in the current directory; an absolute path as written, without the note.
    CHECK(has(shake("no-such-file.txt", "t.deck"), "t.deck:6:14: error: cannot open the motion file 'no-such-file.txt': "));
    CHECK(shake("/no-such-dir/m.txt", "t.deck") == "t.deck:6:14: error: cannot open the motion file '/no-such-dir/m.txt': No such file or directory\n");
}

TEST_CASE("deck error: no GRID, no STEP or no CLUSTER card") {
    CHECK_ONE_ERROR(kMaterial + kCluster + kStep + "END\n", 4, 1, "no GRID card");
    CHECK_ONE_ERROR(kGrid + kMaterial + kCluster + "END\n", 4, 1, "no STEP card");
    CHECK_ONE_ERROR(kGrid + kMaterial + kStep, 3, 1, "no CLUSTER card");  // after the cards, as the others
    // Only comments: both missing cards are named.
    Scene s;
    const Diagnostics d = read_text("* nothing but comments\n! and more\n", s);
    INFO(listing(d));
    REQUIRE(d.size() == 2);
    CHECK(has(d[0].message, "no GRID card"));
    CHECK(has(d[1].message, "no STEP card"));
}

TEST_CASE("deck error: & with no line after it, at the &") {
    CHECK_ONE_ERROR(kGrid + kMaterial + kCluster + "STEP 1E-4 &", 4, 11, "'&' continues the card, but no line follows");
    CHECK_ONE_ERROR(kGrid + kMaterial + kCluster + "STEP 1E-4 &   ! steps below\n", 4, 11, "'&' continues the card, but no line follows");
    CHECK_ONE_ERROR(kBase + "GRAVITY 0 &\n* the last line is a comment card\n", 5, 11, "'&' continues the card, but no line follows");
    CHECK_ONE_ERROR(kBase + "TITLE &\r\n", 5, 7, "'&' continues the card, but no line follows");
}

TEST_CASE("deck error: an empty deck") {
    CHECK_ONE_ERROR("", 1, 1, "the deck is empty");
    CHECK_ONE_ERROR("\n\n  \t\r\n", 1, 1, "the deck is empty");
}

TEST_CASE("deck error: binary data, one message at the first bad byte") {
    CHECK_ONE_ERROR(kGrid + std::string("MAT\0ERIAL\x01\x02\x03\n", 13) + kBase, 2, 4, "the deck holds binary data (byte 0x00)");
    CHECK_ONE_ERROR(std::string("\x7f" "ELF\x02\x01\x01", 7), 1, 1, "binary data (byte 0x7f)");
    CHECK_ONE_ERROR(plus("GRAVITY 0 -9.81 \x1b[0m"), 5, 17, "binary data (byte 0x1b)");
}

TEST_CASE("deck: UTF-8 text in titles and comments is text, not binary") {
    const Scene s = read_ok("TITLE Böschung, φ = 30°\n" + kBase + "! σ_yy in kPa\n");
    CHECK(s.title == "Böschung, φ = 30°");
}

TEST_CASE("deck error: a deck file that cannot be opened") {
    Scene s;
    const Diagnostics d = lpfdm::read_deck("no-such-directory/no-such.deck", s);
    INFO(listing(d));
    REQUIRE(d.size() == 1);
    CHECK(d[0].pos.file == "no-such-directory/no-such.deck");
    CHECK(has(d[0].message, "cannot open the deck"));
    CHECK(has(d[0].str(), "no-such-directory/no-such.deck: error: cannot open the deck"));
}

TEST_CASE("deck: read_deck reads a file and names it in its messages") {
    const std::string path = "test_deck_read_deck.tmp.deck";
    {
        std::ofstream f(path, std::ios::binary);
        f << kBase << "FIX Q 0 0 4 0\n";
    }
    Scene s;
    const Diagnostics d = lpfdm::read_deck(path, s);
    std::remove(path.c_str());
    INFO(listing(d));
    REQUIRE(d.size() == 1);
    CHECK(d[0].str() == path + ":5:5: error: unknown direction 'Q' (X, Y or XY)");
}

TEST_CASE("deck: GNU-style message text: file:line:column: error: message") {
    Scene s;
    const Diagnostics d = read_text(plus("FOO"), s);
    REQUIRE(d.size() == 1);
    CHECK(d[0].str() == "t.deck:5:1: error: unknown card 'FOO'");
}

TEST_CASE("deck: several independent errors in the cards are all reported, one each, in order") {
    Scene s;
    const Diagnostics d = read_text(
        "GRID 4 4 1\n"
        "FOO 1\n"                                        // 2:1 unknown card
        "MATERIAL 1 ELASTIC E=5E7 NU=0.3 RHO=2000\n"
        "GRAVITY 0 g\n"                                  // 4:11 not a number
        "CLUSTER 1 0 0 2 2 PPC=0\n"                      // 5:23 PPC (first problem of the card only)
        "FIX Q 0 0 4 0 7\n"                              // 6:5 direction
        "CLUSTER 1 2 2 4 4\n"
        "STEP 1E-4 10\n"
        "OUTPUT POINTS p.txt EVERY 0\n",                 // 9:27 EVERY
        s);
    INFO(listing(d));
    REQUIRE(d.size() == 5);
    CHECK(d[0].pos.line == 2);
    CHECK(d[0].pos.col == 1);
    CHECK(has(d[0].message, "unknown card 'FOO'"));
    CHECK(d[1].pos.line == 4);
    CHECK(d[1].pos.col == 11);
    CHECK(has(d[1].message, "expected a number"));
    CHECK(d[2].pos.line == 5);
    CHECK(d[2].pos.col == 23);
    CHECK(has(d[2].message, "PPC"));
    CHECK(d[3].pos.line == 6);
    CHECK(d[3].pos.col == 5);
    CHECK(has(d[3].message, "unknown direction"));
    CHECK(d[4].pos.line == 9);
    CHECK(d[4].pos.col == 27);
    CHECK(has(d[4].message, "EVERY n"));
}

TEST_CASE("deck: several independent errors of the scene are all reported, one each") {
    Scene s;
    const Diagnostics d = read_text(
        "GRID 4 4 1\n"
        "MATERIAL 1 ELASTIC E=5E7 NU=0.3 RHO=2000\n"
        "MATERIAL 1 ELASTIC E=6E7 NU=0.3 RHO=2000\n"  // 3: defined twice
        "CLUSTER 2 0 0 2 2\n"                         // 4: material 2 not defined
        "CLUSTER 1 0 0 9 2\n"                         // 5: outside the lattice
        "FIX X 9 9 9 9\n"                             // 6: no node
        "WALL 1 4 1 4 4 -2000 0\n"                    // 7: too fast
        "STEP 1E-4 10\n"
        "OUTPUT HISTORY h.txt EVERY 20\n",            // 9: the last row only (a warning)
        s);
    INFO(listing(d));
    REQUIRE(d.size() == 5);
    const int lines[] = {3, 4, 5, 6, 7};
    const char* phrases[] = {"defined twice", "material 2 is not defined", "outside the lattice", "holds no node", "cells per step"};
    int k = 0;
    for (int line : lines) {
        bool found = false;
        for (const auto& e : d) found |= e.pos.line == line && has(e.message, phrases[k]);
        CAPTURE(line);
        INFO("phrases[k] := " << std::string(phrases[k]));
        CHECK(found);
        ++k;
    }
}

// ============================================= corner cases of the reader ===

// Once wrong: the '&' of a continued TITLE stays in the title ("Sand heap &  pushed by a wall").
TEST_CASE("deck: a continued TITLE joins its lines without the &") {
    const Scene s = read_ok("TITLE Sand heap &\n  pushed by a wall\n" + kBase);
    CHECK(s.title == "Sand heap pushed by a wall");
}

// Once wrong: after END the text is still lexed, so a trailing '&' or a control byte in
// notes after END stops the deck, although the cards there are ignored.
TEST_CASE("deck: text after END is ignored, whatever it holds") {
    read_ok(kBase + "END\nNotes: first run & second run &\n");
    read_ok(kBase + "END\nNotes\x01\x02\n");
}

// Once wrong: "EVERY=5" (the form of every other parameter) gives "missing field: EVERY",
// which does not tell what is wrong. It should be read as EVERY 5, or say how to write it.
TEST_CASE("deck: OUTPUT ... EVERY=5 is read as EVERY 5, or the message shows the form") {
    Scene s;
    const Diagnostics d = read_text(plus("OUTPUT POINTS p.txt EVERY=5"), s);
    INFO(listing(d));
    if (d.empty()) {
        CHECK(s.outputs.at(0).every == 5);
    } else {
        REQUIRE(d.size() == 1);
        CHECK(d[0].pos.line == 5);
        CHECK(d[0].pos.col == 21);
        CHECK(has(d[0].message, "EVERY n"));
        CHECK(!has(d[0].message, "missing field"));
    }
}

// Once wrong: a number beyond the range of a double (1E400, 1E-400) is reported as
// "expected a number, found '1E400'", which it is; the message should say it is out of range.
TEST_CASE("deck error: a number out of the range of double says so") {
    CHECK_ONE_ERROR(plus("MATERIAL 2 ELASTIC E=1E400 NU=0.3 RHO=2000"), 5, 22, "out of range");
    CHECK_ONE_ERROR(plus("MATERIAL 2 ELASTIC E=5E7 NU=1E-400 RHO=2000"), 5, 29, "out of range");
}

// Once wrong: a FIX or WALL box reaching far past the lattice (edges beyond about 9e18
// cells) converts an out-of-range double to an integer and reports "holds no node"; the
// box selects the nodes of the lattice inside it.
TEST_CASE("deck: a FIX or WALL box may reach any distance past the lattice") {
    const Scene s = read_ok(plus("FIX XY -1E30 -1 1E30 0"));
    CHECK(s.fixes.size() == 1);
    read_ok(plus("WALL 1 4 1 1E30 4 -1 0"));
}

// Once wrong: columns count a tab as one column; GNU style (the design's message format)
// counts tab stops every 8 columns, as editors and compilers show them.
TEST_CASE("deck error: columns after a tab follow tab stops every 8 columns") {
    CHECK_ONE_ERROR("GRID\t0\t4\t1\n" + kMaterial + kCluster + kStep, 1, 9, "mx (cells in x) must lie in");
    CHECK_ONE_ERROR(plus("FIX\tQ 0 0 4 0"), 5, 9, "unknown direction 'Q'");
}

// Once wrong: SCATTER < 0 is reported at the value (column 60 here), SCATTER > 0.5 at
// column 1 of the card; both are range errors of the same parameter and belong at its value.
TEST_CASE("deck error: SCATTER above 0.5 is reported at its value") {
    CHECK_ONE_ERROR(plus("MATERIAL 2 MOHR E=5E7 NU=0.3 RHO=2000 PHI=30 C=1E3 SCATTER=0.6"), 5, 60, "SCATTER above 0.5");
}

// Once wrong: when the only CLUSTER card is bad, a second message "no CLUSTER card: the
// scene holds no material" follows the real one: two messages for one problem.
TEST_CASE("deck error: a bad CLUSTER card gives one message, not also 'no CLUSTER card'") {
    CHECK_ONE_ERROR(kGrid + kMaterial + "CLUSTER 1 0 0 2 2 PPC=0\n" + kStep, 3, 23, "PPC must be a whole number in [1, 32]");
}

// A deck with a bad card is checked as a whole too, but not where the answer depends on
// what the bad card meant: an unknown card may be a misspelt MATERIAL, so the clusters
// of an unknown material are not called "undefined" (an echo of the first message).
TEST_CASE("deck: a card error is reported alone, without echoes from the scene check") {
    Scene s;
    const Diagnostics d = read_text(kBase + "FOO 1\nCLUSTER 7 2 2 4 4\n", s);
    INFO(listing(d));
    REQUIRE(d.size() == 1);
    CHECK(d[0].pos.line == 5);
    CHECK(has(d[0].message, "unknown card 'FOO'"));
}

// Once wrong: a line holding only a '!' comment ends a continued card, while a '*'
// comment card does not; a comment should not change what the card says.
TEST_CASE("deck: & continues a card across a '!' comment line too") {
    const Scene s = read_ok("GRID 4 4 &\n   ! the cell side in metres:\n   1\n" + kMaterial + kCluster + kStep);
    CHECK(s.cell_m == 1);
}

// Once wrong: a '&' followed only by blank lines up to the end of the deck is reported as
// "missing field" after the last field, not as a '&' with no line after it.
TEST_CASE("deck error: & followed only by blank lines is a continuation with no line") {
    CHECK_ONE_ERROR(kGrid + kMaterial + kCluster + "STEP 1E-4 &\n\n\n", 4, 11, "'&' continues the card, but no line follows");
}

// Once wrong: a UTF-8 byte order mark (written by some Windows editors, which the CRLF
// rule otherwise serves) makes the first card "unknown card '\xEF\xBB\xBFGRID'" (the
// mark is invisible) and then "no GRID card".
TEST_CASE("deck: a UTF-8 byte order mark before the first card is skipped") {
    CHECK(read_ok("\xEF\xBB\xBF" + kBase).mx == 4);
}

// Once wrong: a deck with old Mac line endings (CR only) is reported as "binary data
// (byte 0x0d)"; the message should name the line endings (or CR be read as a line end).
TEST_CASE("deck: CR-only line endings are read or named as such") {
    Scene s;
    const Diagnostics d = read_text("GRID 4 4 1\rMATERIAL 1 ELASTIC E=5E7 NU=0.3 RHO=2000\rCLUSTER 1 0 0 2 2\rSTEP 1E-4 10\r", s);
    INFO(listing(d));
    if (!d.empty()) {
        REQUIRE(d.size() == 1);
        CHECK(has(d[0].message, "line ending"));
    }
}

// Once wrong: load_file does not see a read error. A directory given as the deck opens
// as a stream, reads nothing, and is reported as "the deck is empty" at line 1 column 1;
// the message should say that the deck cannot be read because it is a directory.
TEST_CASE("deck error: a directory given as the deck is named as such") {
    Scene s;
    const Diagnostics d = lpfdm::read_deck(".", s);
    INFO(listing(d));
    REQUIRE(d.size() == 1);
    CHECK(!has(d[0].message, "empty"));
    CHECK(has(d[0].message, "directory"));
}

// Found in the scene set-up, reached from a deck: a FIX box whose edges lie more
// than 2^31 cells past the lattice passes validate() (which counts nodes in long) but
// Simulation::setup converts the edges to int, which overflows, and fixes no node at
// all: "FIX XY -1E10 -1 1E10 0" leaves the base free and the material falls.
TEST_CASE("deck: a FIX box far past the lattice holds the same nodes as a box just past it") {
    auto settle = [](const std::string& fix) {
        Scene s = read_ok(kGrid + kMaterial + "CLUSTER 1 0 0 4 2\n" + kStep + "GRAVITY 0 -9.81\n" + fix + "\n");
        lpfdm::Simulation sim(s);
        for (int n = 0; n < 50; ++n) sim.step();
        return sim.points().y;
    };
    CHECK(settle("FIX XY -1E10 -1 1E10 0") == settle("FIX XY -1 -1 5 0"));
}

// ======================================================= later cards and --set ===

TEST_CASE("deck: MOTION chooses how points move (CENTRE by default); HOURGLASS gives kappa (off by default)") {
    CHECK(read_ok(kBase).motion == lpfdm::Motion::Default);  // CENTRE, or BILINEAR with MAPPING SMOOTH (Simulation)
    CHECK(read_ok(kBase).hourglass == 0.0);
    CHECK(read_ok(plus("MOTION centre")).motion == lpfdm::Motion::Centre);
    CHECK(read_ok(plus("motion CENTER")).motion == lpfdm::Motion::Centre);
    CHECK(read_ok(plus("MOTION BILINEAR")).motion == lpfdm::Motion::Bilinear);
    CHECK(read_ok(plus("MOTION PAPER")).motion == lpfdm::Motion::Paper);
    CHECK(read_ok(plus("HOURGLASS .05")).hourglass == 0.05);
}

TEST_CASE("deck error: a bad MOTION or HOURGLASS card") {
    CHECK_ONE_ERROR(plus("MOTION SIDEWAYS"), 5, 8, "unknown motion 'SIDEWAYS'");
    CHECK_ONE_ERROR(plus("MOTION"), 5, 7, "missing field");
    CHECK_ONE_ERROR(plus("HOURGLASS 1.5"), 5, 11, "HOURGLASS kappa must lie in [0, 1]");
    CHECK_ONE_ERROR(plus("HOURGLASS 0.1\nHOURGLASS 0.2"), 6, 1, "HOURGLASS is given twice");
}

TEST_CASE("deck: REORDER n sorts the points' storage every n steps; every 50 by default") {
    CHECK(read_ok(kBase).reorder == 50);
    CHECK(read_ok(plus("REORDER 20")).reorder == 20);
    CHECK(read_ok(plus("reorder 0")).reorder == 0);
    Scene s = read_ok(kBase);
    CHECK(lpfdm::apply_setting(s, "REORDER.N", 7).empty());
    CHECK(s.reorder == 7);
}

TEST_CASE("deck error: a bad REORDER card") {
    CHECK_ONE_ERROR(plus("REORDER -1"), 5, 9, "steps between sorts of the points must lie in [0, 1000000000], found '-1'");
    CHECK_ONE_ERROR(plus("REORDER 2.5"), 5, 9, "steps between sorts of the points must be a whole number, found '2.5'");
    CHECK_ONE_ERROR(plus("REORDER"), 5, 8, "missing field: steps between sorts of the points");
    CHECK_ONE_ERROR(plus("REORDER 1\nREORDER 2"), 6, 1, "REORDER is given twice");
}

TEST_CASE("deck: SHIFT moves crowding points apart, RATE=0.1 and ABOVE=1.25 unless given; off without the card") {
    CHECK_FALSE(read_ok(kBase).shift);
    const Scene s = read_ok(plus("SHIFT"));
    CHECK(s.shift);
    CHECK(s.shift_rate == 0.1);
    CHECK(s.shift_above == 1.25);
    CHECK(s.shift_pos.line == 5);
    const Scene t = read_ok(plus("shift above=1.5 rate=0.05"));
    CHECK(t.shift_rate == 0.05);
    CHECK(t.shift_above == 1.5);
    CHECK(read_ok(plus("SHIFT ABOVE=1")).shift_above == 1);  // from the first crowding
    Scene u = t;
    CHECK(lpfdm::apply_setting(u, "SHIFT.RATE", 0.2).empty());
    CHECK(u.shift_rate == 0.2);
    Scene v = read_ok(kBase);
    CHECK(lpfdm::apply_setting(v, "SHIFT.RATE", 0.2) == "the deck has no SHIFT card: SHIFT.RATE would change nothing");
}

TEST_CASE("deck error: a bad SHIFT card") {
    CHECK_ONE_ERROR(plus("SHIFT RATE=0"), 5, 12, "RATE must lie in (0, 1]");
    CHECK_ONE_ERROR(plus("SHIFT RATE=1.5"), 5, 12, "RATE must lie in (0, 1]");
    CHECK_ONE_ERROR(plus("SHIFT ABOVE=0.9"), 5, 13, "ABOVE must lie in [1, 4]");
    CHECK_ONE_ERROR(plus("SHIFT 0.1"), 5, 7, "extra field '0.1'");
    CHECK_ONE_ERROR(plus("SHIFT SPEED=1"), 5, 7, "unknown parameter 'SPEED' (this card takes RATE, ABOVE)");
    CHECK_ONE_ERROR(plus("SHIFT\nSHIFT RATE=0.2"), 6, 1, "SHIFT is given twice");
}

TEST_CASE("deck: ADVECT chooses how the nodal increments follow the material; EQ12 by default") {
    CHECK(read_ok(kBase).advect == lpfdm::Advect::Eq12);
    CHECK(read_ok(plus("ADVECT eq12")).advect == lpfdm::Advect::Eq12);
    CHECK(read_ok(plus("MOTION CENTRE\nADVECT POINTS")).advect == lpfdm::Advect::Points);
    CHECK(read_ok(plus("advect points\nmotion bilinear")).advect == lpfdm::Advect::Points);
    CHECK(read_ok(plus("ADVECT POINTS")).advect == lpfdm::Advect::Points);  // the default motion is CENTRE
    CHECK(read_ok(plus("MAPPING SMOOTH\nADVECT FLIP")).advect == lpfdm::Advect::Flip);
    CHECK(read_ok(plus("advect flip\nmapping smooth\nmotion bilinear")).advect == lpfdm::Advect::Flip);
    CHECK(read_ok(plus("MAPPING SMOOTH\nADVECT FLIP\nFIX XY 0 0 4 0")).advect == lpfdm::Advect::Flip);
    CHECK(read_ok(plus("MAPPING SMOOTH\nADVECT FLIP\nWALL 3 0 4 4 4 0 -0.01")).walls.size() == 1);  // walls: test_mapping.cpp
    CHECK(read_ok(plus("MAPPING SMOOTH\nADVECT FLIP\nABSORB BOTTOM")).absorb != 0);                  // ABSORB and SHAKE: test_quake.cpp
}

TEST_CASE("deck error: a bad ADVECT card, ADVECT POINTS with the paper's motion, ADVECT FLIP without MAPPING SMOOTH") {
    CHECK_ONE_ERROR(plus("ADVECT FLOP"), 5, 8, "unknown advection 'FLOP' (EQ12, POINTS or FLIP)");
    CHECK_ONE_ERROR(plus("ADVECT FLIP"), 5, 1, "ADVECT FLIP needs MAPPING SMOOTH");
    CHECK_ONE_ERROR(plus("MAPPING PAPER\nADVECT FLIP"), 6, 1, "ADVECT FLIP needs MAPPING SMOOTH");
    CHECK_ONE_ERROR(plus("MAPPING SMOOTH\nADVECT FLIP\nMOTION CENTRE"), 6, 1, "ADVECT FLIP needs MOTION BILINEAR");
    CHECK_ONE_ERROR(plus("ADVECT"), 5, 7, "missing field");
    CHECK_ONE_ERROR(plus("ADVECT POINTS 2"), 5, 15, "extra field '2'");
    CHECK_ONE_ERROR(plus("MOTION CENTRE\nADVECT POINTS\nADVECT EQ12"), 7, 1, "ADVECT is given twice");
    CHECK_ONE_ERROR(plus("ADVECT POINTS\nMOTION PAPER"), 5, 1, "ADVECT POINTS needs MOTION CENTRE or BILINEAR");
}

TEST_CASE("apply_setting: CARD.PARAM overrides what the deck said, and names what it cannot") {
    lpfdm::Scene s = read_ok(plus("WALL 3 0 4 4 4 0 -0.01") + "DAMPING 0.8\n");
    CHECK(lpfdm::apply_setting(s, "material1.e", 6e7).empty());
    CHECK(s.materials[0].E == 6e7);
    CHECK(lpfdm::apply_setting(s, "CLUSTER1.PPC", 4).empty());
    CHECK(s.clusters[0].ppc == 4);
    CHECK(lpfdm::apply_setting(s, "WALL3.VY", -0.02).empty());
    CHECK(s.walls[0].vy == -0.02);
    CHECK(lpfdm::apply_setting(s, "DAMPING.ALPHA", 0).empty());
    CHECK(s.damping == 0.0);
    CHECK(lpfdm::apply_setting(s, "STEP.N", 77).empty());
    CHECK(s.steps == 77);
    CHECK(lpfdm::apply_setting(s, "HOURGLASS.KAPPA", 0.1).empty());
    CHECK(s.hourglass == 0.1);
    CHECK(lpfdm::apply_setting(s, "MATERIAL9.C", 1) == "no MATERIAL with id 9");
    CHECK(lpfdm::apply_setting(s, "CLUSTER2.PPC", 1).find("no CLUSTER number 2") != std::string::npos);
    CHECK(lpfdm::apply_setting(s, "CLUSTER1.PPC", 2.5) == "PPC must be a whole number in [1, 32]");
    CHECK(lpfdm::apply_setting(s, "MATERIAL1.FOO", 1).find("MATERIAL has no parameter FOO (it takes E, NU, RHO") == 0);
    CHECK(lpfdm::apply_setting(s, "NOPE", 1).find("CARD.PARAM") != std::string::npos);
    CHECK(lpfdm::apply_setting(s, "STEP.N", 0).find("whole number") != std::string::npos);
    CHECK(lpfdm::validate(s).empty());
    // The range of each key is the deck reader's (kDeckKeys): refused at once, the scene unchanged.
    CHECK(lpfdm::apply_setting(s, "DAMPING.ALPHA", 1.5) == "DAMPING alpha must lie in [0, 1)");
    CHECK(s.damping == 0.0);
    CHECK(lpfdm::apply_setting(s, "MATERIAL1.NU", 0.5) == "NU must lie in (-1, 0.5)");
    CHECK(lpfdm::apply_setting(s, "CLUSTER1.PPC", 1e300) == "PPC must be a whole number in [1, 32]");
    CHECK(lpfdm::apply_setting(s, "MATERIAL1.ID", 3).find("MATERIAL has no parameter ID") == 0);
    CHECK(lpfdm::validate(s).empty());
}

TEST_CASE("apply_setting: a key the material's model does not use is an error, not a silent no-op") {
    lpfdm::Scene s = read_ok(kGrid + "MATERIAL 1 ELASTIC E=2E7 NU=0.25 RHO=2000\nMATERIAL 2 MOHR E=5E7 NU=0.3 RHO=1700 PHI=30 C=1E4\n" + kCluster + kStep + "OUTPUT HISTORY h.txt EVERY 2\n");
    const std::string e = lpfdm::apply_setting(s, "MATERIAL1.PHI", 30);
    CHECK(e == "MATERIAL 1 is ELASTIC: PHI is not one of its parameters (E, NU, RHO, POROSITY, PERM)");
    CHECK(lpfdm::apply_setting(s, "MATERIAL2.PHI", 25).empty());
    CHECK(s.materials[1].phi_deg == 25);
    CHECK(lpfdm::apply_setting(s, "MATERIAL2.PSI", 26) == "PSI must lie in [0, PHI]");  // PHI is 25 now
    CHECK(s.materials[1].psi_deg == 0);
    CHECK(lpfdm::apply_setting(s, "OUTPUT1.EVERY", 3).empty());
}

TEST_CASE("one table of cards and keys: --help lists it, decks/README.md documents every card and key") {
    const std::string help = lpfdm::deck_help();
    std::ifstream in("decks/README.md");
    REQUIRE(in);
    std::stringstream ss;
    ss << in.rdbuf();
    const std::string doc = ss.str();
    for (const lpfdm::DeckCard& c : lpfdm::kDeckCards) {
        INFO("card " << std::string(c.name));
        CHECK(help.find(std::string("  ") + c.name) != std::string::npos);
        CHECK(doc.find(std::string("| `") + c.name) != std::string::npos);  // a row of the card table
    }
    for (const lpfdm::DeckKey& k : lpfdm::kDeckKeys) {
        INFO("key " << std::string(k.card) << "." << std::string(k.name));
        if (k.param) CHECK(doc.find(std::string(k.name) + "=") != std::string::npos);  // in its card's synopsis
        if (!k.settable) continue;
        // the --set table: a row "| `CARD<..>` | `KEY`, ... |"
        const std::size_t row = doc.find(std::string("| `") + k.card + (std::strcmp(k.card, "MATERIAL") == 0 || std::strcmp(k.card, "WALL") == 0 ? "<id>` |" : std::strcmp(k.card, "CLUSTER") == 0 || std::strcmp(k.card, "FIX") == 0 || std::strcmp(k.card, "SHAKE") == 0 || std::strcmp(k.card, "OUTPUT") == 0 || std::strcmp(k.card, "TRACK") == 0 || std::strcmp(k.card, "DRAIN") == 0 || std::strcmp(k.card, "LOAD") == 0 ? "<n>` |" : "` |"));
        REQUIRE(row != std::string::npos);
        const std::string line = doc.substr(row, doc.find('\n', row) - row);
        CHECK(line.find(std::string("`") + k.name + "`") != std::string::npos);
    }
    // CLUSTER's FILL=, a word the table of keys does not hold: in --help and the card table
    CHECK(help.find("[FILL=CELLS]") != std::string::npos);
    CHECK(help.find("FILL=POINTS") != std::string::npos);
    CHECK(doc.find("| `CLUSTER ... FILL=POINTS` |") != std::string::npos);
}

TEST_CASE("a misspelt card, parameter or --set key is named with the closest one of the table") {
    CHECK_ONE_ERROR(plus("CLUSTR 1 2 2 4 4"), 5, 1, "unknown card 'CLUSTR' (did you mean CLUSTER?)");
    CHECK_ONE_ERROR(plus("GRAV 0 -9.81"), 5, 1, "(did you mean GRAVITY?)");  // a beginning
    CHECK_ONE_ERROR(plus("CLUSTER 1 2 2 4 4 PCC=3"), 5, 19, "(did you mean PPC?)");  // two letters swapped
    CHECK_ONE_ERROR(plus("MATERIAL 2 MOHR E=5E7 NU=0.3 RHO=2000 PHI=30 C=0 SOFTNE=0.5"), 5, 50, "(did you mean SOFTEN?)");
    lpfdm::Scene s;
    CHECK(read_text(plus("FOO 1 2"), s)[0].message.find("did you mean") == std::string::npos);  // nothing close
    CHECK(lpfdm::did_you_mean("dampng", lpfdm::card_names()) == " (did you mean DAMPING?)");
    CHECK(lpfdm::did_you_mean("XYZZY", lpfdm::card_names()).empty());
    CHECK(lpfdm::nearest_name("clustr", lpfdm::card_names()) == "CLUSTER");
    CHECK(lpfdm::nearest_name("XYZZY", lpfdm::card_names()).empty());
    lpfdm::Scene t = read_ok(plus("DAMPING 0.5"));
    CHECK(lpfdm::apply_setting(t, "DAMPING.ALPAH", 0.1).find("(did you mean ALPHA?)") != std::string::npos);
    CHECK(lpfdm::apply_setting(t, "DAMPNIG.ALPHA", 0.1).find("(did you mean DAMPING?)") != std::string::npos);
}

// ======================================== one pass: every error, and warnings ===

// The reader's errors and the scene check's come from one pass, in the order of the deck:
// a deck with mistakes of both kinds is fixed in one edit, not in rounds.
TEST_CASE("deck: errors of the cards and of the scene in one pass, in the order of the deck") {
    Scene s;
    const Diagnostics d = read_text(
        "GRID 4 4 1\n"
        "MATERIAL 1 ELASTIC E=5E7 NU=0.3 RHO=2000\n"
        "CLUSTER 1 0 0 9 2\n"                          // 3:1 outside the lattice (scene)
        "FIX Q 0 0 4 0\n"                              // 4:5 direction (card)
        "FIX X 9 9 9 9\n"                              // 5:1 no node (scene)
        "GRAVITY 0 g\n"                                // 6:11 not a number (card)
        "WALL 1 4 1 4 4 -2000 0\n"                     // 7:1 too fast (scene)
        "STEP 1E-4 10\n",
        s);
    INFO(listing(d));
    REQUIRE(d.size() == 5);
    const int where[][2] = {{3, 1}, {4, 5}, {5, 1}, {6, 11}, {7, 1}};
    const char* phrases[] = {"outside the lattice", "unknown direction", "holds no node", "expected a number", "cells per step"};
    for (int k = 0; k < 5; ++k) {
        CAPTURE(k);
        CHECK(d[std::size_t(k)].pos.line == where[k][0]);
        CHECK(d[std::size_t(k)].pos.col == where[k][1]);
        CHECK(has(d[std::size_t(k)].message, phrases[k]));
        CHECK(!d[std::size_t(k)].warning);
    }
}

// What a bad card leaves out is not checked again: one message per problem.
TEST_CASE("deck: a bad card's consequences are not reported as more errors") {
    // a bad STEP: not also "dt must be > 0", nor a wall too fast for the dt it did not set
    CHECK_ONE_ERROR(kGrid + kMaterial + kCluster + "STEP 0 10\n", 4, 6, "the time step dt must be > 0");
    CHECK_ONE_ERROR(kGrid + kMaterial + kCluster + "STEP 1E-4 ten\nWALL 1 4 1 4 4 -1 0\n", 4, 11, "expected a number");
    // a bad GRID: no box is "outside the lattice", no FIX "holds no node"
    CHECK_ONE_ERROR("GRID 4 4 -1\n" + kMaterial + kCluster + kStep + "FIX X 0 0 4 0\n", 1, 10, "the cell size L must be > 0");
    CHECK_ONE_ERROR("GRID 4 4\n" + kMaterial + kCluster + kStep, 1, 9, "missing field: L");
    // a bad MATERIAL: its clusters are not "undefined"; no GRID: only that is said
    CHECK_ONE_ERROR(kGrid + "MATERIAL 1 ELASTIC E=5E7 NU=0.7 RHO=2000\n" + kCluster + kStep, 2, 29, "NU must lie in");
    CHECK_ONE_ERROR(kMaterial + kCluster + kStep, 3, 1, "no GRID card");
    // a bad ADVECT or MOTION card: not also "ADVECT POINTS needs MOTION CENTRE"
    CHECK_ONE_ERROR(plus("MOTION CENTR\nADVECT POINTS"), 5, 8, "unknown motion 'CENTR'");
    // a scene error still shows beside a card error that has nothing to do with it
    Scene s;
    const Diagnostics d = read_text(kBase + "FIX Q 0 0 4 0\nFIX X 9 9 9 9\n", s);
    INFO(listing(d));
    REQUIRE(d.size() == 2);
    CHECK(has(d[0].message, "unknown direction"));
    CHECK(has(d[1].message, "holds no node"));
}

TEST_CASE("diagnostics sort by file, line and column, keeping the order within a place") {
    Diagnostics d = lpfdm::one_error("b.deck", 1, 1, "b");
    for (const auto& e : {lpfdm::one_error("a.deck", 9, 2, "late"), lpfdm::one_error("a.deck", 9, 1, "first"), lpfdm::one_error("a.deck", 9, 1, "second")})
        d.push_back(e[0]);
    lpfdm::sort_diagnostics(d);
    REQUIRE(d.size() == 4);
    CHECK(d[0].message == "first");
    CHECK(d[1].message == "second");
    CHECK(d[2].message == "late");
    CHECK(d[3].message == "b");
}

// One warning per rule at the card it concerns, and none for sensible numbers: the warnings
// are for numbers that are legal but probably in the wrong unit or mistyped.
TEST_CASE("deck warnings: radians, angles above 60 degrees, kPa, t/m^3, NU near 0.5") {
    struct Case {
        const char* material;
        const char* phrase;
    } cases[] = {
        {"MATERIAL 2 MOHR E=5E7 NU=0.3 RHO=2000 PHI=0.52 C=1E3", "PHI = 0.52 degrees: is it in radians (29.8 degrees)?"},
        {"MATERIAL 2 MOHR E=5E7 NU=0.3 RHO=2000 PHI=30 C=1E3 PSI=0.1", "PSI = 0.1 degrees: is it in radians"},
        {"MATERIAL 2 MOHR E=5E7 NU=0.3 RHO=2000 PHI=62 C=1E3", "PHI = 62 degrees is above 60"},
        {"MATERIAL 2 ELASTIC E=50 NU=0.3 RHO=2000", "E = 50 Pa is below 1 kPa"},
        {"MATERIAL 2 ELASTIC E=5E7 NU=0.3 RHO=2", "RHO = 2 kg/m^3 is below 100"},
        {"MATERIAL 2 ELASTIC E=5E7 NU=0.495 RHO=2000", "NU = 0.495 is nearly incompressible"},
    };
    for (const Case& c : cases) {
        INFO("c.material := " << std::string(c.material));
        const Scene s = read_ok(plus(c.material));
        const Diagnostics w = lpfdm::warnings(s);
        INFO(listing(w));
        REQUIRE(w.size() == 1);
        CHECK(w[0].warning);
        CHECK(w[0].pos.line == 5);
        CHECK(w[0].pos.col == 1);
        CHECK(has(w[0].str(), "t.deck:5:1: warning: "));
        CHECK(has(w[0].message, c.phrase));
    }
    for (const char* fine : {"MATERIAL 2 MOHR E=1E3 NU=0.494 RHO=100 PHI=1.6 C=1E3 PSI=0", "MATERIAL 2 MOHR E=5E7 NU=0.3 RHO=2000 PHI=60 C=1E3 PSI=1.6",
                             "MATERIAL 2 MOHR E=5E7 NU=0.3 RHO=2000 PHI=0 C=1E3"}) {
        INFO("fine := " << std::string(fine));
        const Diagnostics w = lpfdm::warnings(read_ok(plus(fine)));
        INFO(listing(w));
        CHECK(w.empty());
    }
}

TEST_CASE("deck warnings: a time step above 0.95 of the stable limit; an output interval longer than the run") {
    Scene s = read_ok(kBase);
    const double lim = lpfdm::stable_dt(s);
    s.dt_s = 0.96 * lim;
    Diagnostics w = lpfdm::warnings(s);
    INFO(listing(w));
    REQUIRE(w.size() == 1);
    CHECK(w[0].pos.line == 4);
    CHECK(has(w[0].message, "0.960 of the stable limit"));
    s.dt_s = 0.94 * lim;
    CHECK(lpfdm::warnings(s).empty());
    s.dt_s = 1.01 * lim;  // above the limit: an error of validate(), not also a warning
    CHECK(lpfdm::warnings(s).empty());
    CHECK(!lpfdm::validate(s).empty());
    const Scene p = read_ok(plus("OUTPUT POINTS p.txt EVERY 11"));
    w = lpfdm::warnings(p);
    REQUIRE(w.size() == 1);
    CHECK(has(w[0].message, "EVERY 11 is more than the 10 steps of the run: only the first and last frames are written"));
}

// ADVECT FLIP with one point a cell (test_energy.cpp shows why): at the cluster's card,
// whichever cluster it is; none with two or more, or without FLIP.
TEST_CASE("deck warnings: ADVECT FLIP with PPC=1") {
    const std::string flip = "MAPPING SMOOTH\nADVECT FLIP\n";
    Diagnostics w = lpfdm::warnings(read_ok(kGrid + kMaterial + "CLUSTER 1 0 0 2 2 PPC=1\n" + kStep + flip));
    INFO(listing(w));
    REQUIRE(w.size() == 1);
    CHECK(w[0].pos.line == 3);
    CHECK(has(w[0].message, "ADVECT FLIP with PPC=1: a checkerboard of the points' increments is invisible to the lattice"));
    w = lpfdm::warnings(read_ok(kBase + "CLUSTER 1 2 2 4 4 PPC=1\n" + flip));
    REQUIRE(w.size() == 1);
    CHECK(w[0].pos.line == 5);
    CHECK(lpfdm::warnings(read_ok(kGrid + kMaterial + "CLUSTER 1 0 0 2 2 PPC=2\n" + kStep + flip)).empty());
    CHECK(lpfdm::warnings(read_ok(kGrid + kMaterial + "CLUSTER 1 0 0 2 2 PPC=1\n" + kStep + "MAPPING SMOOTH\n")).empty());
}

// The shipped decks are meant as written: none draws a warning.
TEST_CASE("deck warnings: none for the decks in decks/") {
    for (const auto& e : std::filesystem::directory_iterator("decks")) {
        if (e.path().extension() != ".deck") continue;
        CAPTURE(e.path().string());
        Scene s;
        const Diagnostics d = lpfdm::read_deck(e.path().string(), s);
        INFO(listing(d));
        CHECK(d.empty());
        const Diagnostics w = lpfdm::warnings(s);
        INFO(listing(w));
        CHECK(w.empty());
    }
}

// ================================================================ provenance ===

TEST_CASE("provenance: FNV-1a 64 of the deck text") {
    CHECK(lpfdm::fnv1a64("") == 0xcbf29ce484222325ull);
    CHECK(lpfdm::fnv1a64("a") == 0xaf63dc4c8601ec8cull);
    CHECK(lpfdm::fnv1a64("foobar") == 0x85944171f73967e8ull);
}

TEST_CASE("provenance: the '# run:' lines record version, deck digest, options, seed, steps, threads, kernel") {
    Scene s = read_ok(kBase + "SEED 7\n");
    lpfdm::Simulation sim(s);
    lpfdm::RunInfo r;
    r.deck = "dir/x.deck";
    r.deck_digest = lpfdm::fnv1a64(kBase);
    r.settings = {"MATERIAL1.E=6E7", "STEP.N=10"};
    r.steps = 10;
    r.refine = 2;
    r.threads = 3;
    r.kernel = "scalar";
    std::FILE* f = std::tmpfile();
    REQUIRE(f);
    lpfdm::write_provenance(f, sim, r);
    std::rewind(f);
    std::string text;
    for (int ch; (ch = std::fgetc(f)) != EOF;) text += char(ch);
    std::fclose(f);
    INFO(text);
    char digest[32];
    std::snprintf(digest, sizeof digest, "%016llx", static_cast<unsigned long long>(lpfdm::fnv1a64(kBase)));
    CHECK(has(text, std::string("# run: lpfdm ") + lpfdm::kVersion + "\n"));
    CHECK(has(text, std::string("# run: deck dir/x.deck (fnv1a64 ") + digest + ")\n"));
    CHECK(has(text, "# run: options --steps 10 --refine 2 --set MATERIAL1.E=6E7 --set STEP.N=10\n"));
    CHECK(has(text, "# run: seed 7 steps 10 dt 0.0001 s\n"));
    CHECK(has(text, "# run: threads 3 kernel scalar\n"));
    std::istringstream lines(text);
    for (std::string line; std::getline(lines, line);) CHECK(line.rfind("# run: ", 0) == 0);
}

TEST_CASE("restart: a state file whose points do not fit the scene is refused, checksum and all") {
    // A soft Mohr-Coulomb block under gravity: points yield within the first steps.
    const std::string deck =
        "GRID 8 8 0.5\n"
        "MATERIAL 1 MOHR E=2E7 NU=0.25 RHO=2000 PHI=30 C=10\n"
        "CLUSTER 1 0 0 4 2\n"
        "FIX XY 0 0 4 0\n"
        "GRAVITY 0 -9.81\n"
        "STEP 1E-3 200\n";
    Scene s = read_ok(deck);
    lpfdm::Simulation sim(s);
    for (int n = 0; n < 200; ++n) sim.step();
    std::size_t yielded = 0;
    for (std::uint8_t y : sim.points().yielded) yielded += y;
    REQUIRE(yielded > 0);
    const std::filesystem::path dir = std::filesystem::temp_directory_path() / ("lpfdm_test_state." + std::to_string(::getpid()));  // (the two builds of make test run at once)
    std::filesystem::create_directories(dir);
    const std::string good = (dir / "good.state").string(), bad = (dir / "bad.state").string();
    std::FILE* f = std::fopen(good.c_str(), "wb");
    REQUIRE(f);
    REQUIRE(lpfdm::write_state(f, sim, 42));
    std::fclose(f);
    std::ifstream in(good, std::ios::binary);
    const std::string written((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    {
        lpfdm::Simulation fresh(s);
        CHECK(lpfdm::read_state(good, fresh, 42).empty());  // the file as written is read
    }
    // The first value of item `name` ("point_x"...): after u8 length, the name, u8 bytes per value, u64 count.
    auto first_value = [&](const std::string& name) {
        const std::size_t at = written.find(char(name.size()) + name);
        REQUIRE(at != std::string::npos);
        return at + 1 + name.size() + 1 + 8;
    };
    // The file edited by `edit`, its checksum mended, is refused with `phrase`; the simulation is left as it was.
    auto refused = [&](const std::function<void(std::string&)>& edit, const std::string& phrase) {
        std::string b = written;
        edit(b);
        const std::uint64_t sum = lpfdm::fnv1a64(b.substr(0, b.size() - 8));  // (its checksum: FNV-1a of the bytes before it)
        std::memcpy(&b[b.size() - 8], &sum, 8);
        std::ofstream(bad, std::ios::binary) << b;
        lpfdm::Simulation fresh(s);
        const Diagnostics d = lpfdm::read_state(bad, fresh, 42);
        REQUIRE(d.size() == 1);
        INFO(listing(d));
        CHECK(has(d[0].str(), "does not fit this scene"));
        CHECK(has(d[0].str(), phrase));
        CHECK(fresh.step_count() == 0);
    };
    refused([&](std::string& b) {  // a point that yielded: its flag becomes 2
        const std::size_t first = first_value("point_yielded");
        std::size_t k = 0;
        while (b[first + k] != 1) ++k;
        b[first + k] = 2;
    }, "yielded flag 2, not 0 or 1");
    refused([&](std::string& b) {  // point 0 moved one cell to the right of the cell it is listed in
        const std::size_t at = first_value("point_x");
        double x;
        std::memcpy(&x, &b[at], 8);
        x += 0.5;
        std::memcpy(&b[at], &x, 8);
    }, "not in its cell");
    refused([&](std::string& b) {  // point 0 at x = NaN
        const std::size_t at = first_value("point_x");
        const double x = std::nan("");
        std::memcpy(&b[at], &x, 8);
    }, "not in its cell");
    std::filesystem::remove_all(dir);
}

// The point table's ux uy: each point's displacement since step 0, x - x0 and y - y0 by its
// id, whatever the storage order. A block falling freely (decks/freefall.deck, before it
// reaches the floor) moves rigidly: every point has ux = 0 and the same uy, the block's
// fall, g t^2 / 2 to first order in dt.
TEST_CASE("point table: ux uy are the displacement since step 0, by id") {
    using namespace lpfdm;
    Scene s;
    REQUIRE(read_deck("decks/freefall.deck", s).empty());
    s.reorder = 7;  // storage sorted anew: the table must still pair each point with its own start
    Simulation sim(s);
    const std::vector<double> x0 = sim.points().x, y0 = sim.points().y;  // at step 0 the storage is id order
    const long n = 1000;
    for (long k = 0; k < n; ++k) sim.step();
    std::FILE* f = std::tmpfile();
    REQUIRE(f);
    write_points_header(f, sim, "freefall");
    write_points_frame(f, sim, true);
    std::rewind(f);
    char line[512];
    REQUIRE(std::fgets(line, sizeof line, f));
    CHECK(std::string(line) == "x y sxx syy sxy szz ep yielded mat id ux uy\n");
    const double t = double(n) * s.dt_s, fall = 0.5 * 9.81 * t * t;
    long rows = 0;
    double uy_first = 0;
    while (std::fgets(line, sizeof line, f)) {
        if (line[0] == '#' || line[0] == '\n') continue;
        double x, y, sxx, syy, sxy, szz, ep, ux, uy;
        int yielded, mat, id;
        REQUIRE(std::sscanf(line, "%lf %lf %lf %lf %lf %lf %lf %d %d %d %lf %lf", &x, &y, &sxx, &syy, &sxy, &szz, &ep, &yielded, &mat, &id, &ux, &uy) == 12);
        const std::size_t i = std::size_t(id);
        CHECK(ux == approx(x - x0[i]).epsilon(1e-6).scale(1e-9));  // (x printed to 9 digits, ux to 7)
        CHECK(uy == approx(y - y0[i]).epsilon(1e-6).scale(1e-9));
        CHECK(std::fabs(ux) < 1e-12);
        if (rows == 0) uy_first = uy;
        CHECK(uy == approx(uy_first).epsilon(1e-9));  // rigid
        ++rows;
    }
    std::fclose(f);
    CHECK(rows == long(sim.points().size()));
    CHECK(-uy_first == approx(fall).epsilon(2 * s.dt_s / t + 1e-3));  // the leapfrog's fall: g t (t + dt) / 2 or so
}

// TRACK x y: the history follows the point nearest (x, y) at step 0 (tN_x tN_y tN_ux tN_uy,
// after the other columns, so theirs keep their numbers); --set TRACKn.X moves card n.
TEST_CASE("TRACK: the history follows a point: its place and its displacement since step 0") {
    using namespace lpfdm;
    std::string text;
    REQUIRE(load_file("decks/freefall.deck", text).empty());
    text = text.substr(0, text.rfind("END")) + "TRACK 0.5 2.5\nTRACK 0.1 2.1\nEND\n";
    Scene s;
    REQUIRE(read_deck_text(text, "freefall+track", s).empty());
    REQUIRE(s.tracks.size() == 2);
    CHECK(s.tracks[1].x == 0.1);
    CHECK(apply_setting(s, "TRACK2.Y", 2.2).empty());
    CHECK(s.tracks[1].y == 2.2);
    CHECK(apply_setting(s, "TRACK3.X", 0).find("there is no TRACK number 3") != std::string::npos);
    s.tracks[1].y = 2.1;
    Simulation sim(s);
    // The nearest points at step 0: (0.5, 2.5) lies on four points' corner, the lowest id
    // of them taken; (0.1, 2.1) is nearest the block's corner point (0.0625, 2.0625).
    REQUIRE(sim.tracked().size() == 2);
    const auto& p = sim.points();
    CHECK(p.x[std::size_t(sim.tracked()[1])] == 0.0625);
    CHECK(p.y[std::size_t(sim.tracked()[1])] == 2.0625);
    CHECK(std::hypot(p.x[std::size_t(sim.tracked()[0])] - 0.5, p.y[std::size_t(sim.tracked()[0])] - 2.5) == approx(std::hypot(0.0625, 0.0625)).epsilon(1e-12));
    const std::string cols = history_columns(sim);
    const std::string tail = " t1_x t1_y t1_ux t1_uy t2_x t2_y t2_ux t2_uy";
    REQUIRE(cols.size() > tail.size());
    CHECK(cols.compare(cols.size() - tail.size(), tail.size(), tail) == 0);
    for (int k = 0; k < 1000; ++k) sim.step();
    std::FILE* f = std::tmpfile();
    REQUIRE(f);
    write_history_row(f, sim);
    std::rewind(f);
    char line[4096];
    REQUIRE(std::fgets(line, sizeof line, f));
    std::fclose(f);
    std::vector<double> v;
    for (const char* c = line; *c;) {
        char* end = nullptr;
        const double x = std::strtod(c, &end);
        if (end == c) break;
        v.push_back(x);
        c = end;
    }
    REQUIRE(v.size() >= 8);
    const std::size_t n = v.size();
    const std::int32_t id = sim.tracked()[1];
    const long k = sim.slot_of(id);
    REQUIRE(k >= 0);
    CHECK(v[n - 4] == approx(p.x[std::size_t(k)]).epsilon(1e-8));
    CHECK(v[n - 3] == approx(p.y[std::size_t(k)]).epsilon(1e-8));
    CHECK(v[n - 2] == approx(0.0).scale(1e-12));
    CHECK(v[n - 1] == approx(p.y[std::size_t(k)] - 2.0625).epsilon(1e-6));
    CHECK(v[n - 1] == approx(v[n - 5]).epsilon(1e-9));  // the block falls rigidly: both points alike
}

// Material over an opening: under gravity, a column of cells with no fixed or walled row of
// nodes beneath its material down to the lattice's edge falls out there (a row of cells
// for a horizontal gravity); OUTFLOW says it is meant, an ABSORB edge holds.
TEST_CASE("deck warning: material over an opening in its support falls out of the lattice, unless OUTFLOW names the edge") {
    const std::string bin = "GRID 4 4 1\nMATERIAL 1 ELASTIC E=5E7 NU=0.3 RHO=2000\nCLUSTER 1 0 2 4 4\nSTEP 1E-4 10\n"
                            "GRAVITY 0 -9.81\nFIX XY 0 2 1 2\nFIX XY 3 2 4 2\n";  // a floor at y = 2 with a hole from x = 1 to 3
    Diagnostics w = lpfdm::warnings(read_ok(bin));
    INFO(listing(w));
    REQUIRE(w.size() == 1);
    CHECK(w[0].pos.line == 3);  // the CLUSTER whose material is over it
    CHECK(has(w[0].message, "falls out through the lattice's BOTTOM edge under gravity: 2 columns of cells (the first 1 to 2, x = 1 to 3 m)"));
    CHECK(has(w[0].message, "OUTFLOW BOTTOM says it is meant"));
    CHECK(lpfdm::warnings(read_ok(bin + "OUTFLOW BOTTOM\n")).empty());
    CHECK(lpfdm::warnings(read_ok(bin + "OUTFLOW LEFT BOTTOM\n")).empty());
    CHECK(lpfdm::warnings(read_ok(bin + "ABSORB BOTTOM\n")).empty());
    CHECK(lpfdm::warnings(read_ok(bin + "FIX Y 0 0 4 0\n")).empty());      // a floor lower down catches it
    CHECK(lpfdm::warnings(read_ok(bin + "WALL 1 1 1 3 1 0 0\n")).empty());  // so does a wall
    CHECK(!lpfdm::warnings(read_ok(bin + "FIX X 0 0 4 0\n")).empty());      // held across, not against gravity
    CHECK(lpfdm::warnings(read_ok(kBase + "FIX XY 0 0 4 0\nGRAVITY 0 -9.81\n")).empty());
    // Sideways: gravity along +x and nothing holding the lattice's right edge
    w = lpfdm::warnings(read_ok(kBase + "FIX XY 0 0 4 0\nGRAVITY 9.81 0\n"));
    INFO(listing(w));
    REQUIRE(w.size() == 1);
    CHECK(has(w[0].message, "RIGHT edge under gravity: 2 rows of cells (the first 0 to 1, y = 0 to 2 m)"));
    CHECK(lpfdm::warnings(read_ok(kBase + "FIX XY 0 0 4 0\nGRAVITY 9.81 0\nFIX X 4 0 4 4\n")).empty());
    // A smooth wall holds across its line only: a base stopping short of its lowest node
    // leaves that cell open (the backfill drained out there); the base reaching it holds.
    const std::string wall = "GRID 8 4 1\nMATERIAL 1 ELASTIC E=5E7 NU=0.3 RHO=2000\nCLUSTER 1 2 0 8 2\nSTEP 1E-4 10\nGRAVITY 0 -9.81\n"
                             "WALL 1 2 0 2 4 0 0 SMOOTH\n";
    w = lpfdm::warnings(read_ok(wall + "FIX Y 3 0 8 0\n"));
    INFO(listing(w));
    REQUIRE(w.size() == 1);
    CHECK(has(w[0].message, "BOTTOM edge under gravity: 1 column of cells (the first 2 to 2, x = 2 to 3 m)"));
    CHECK(lpfdm::warnings(read_ok(wall + "FIX Y 2 0 8 0\n")).empty());
    // OUTFLOW's own errors
    CHECK_ONE_ERROR(plus("OUTFLOW SIDEWAYS"), 5, 9, "edge");
    CHECK_ONE_ERROR(plus("OUTFLOW BOTTOM BOTTOM"), 5, 1, "OUTFLOW BOTTOM is given twice");
}
