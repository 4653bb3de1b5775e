// The reference cycle is the definition of a step: every fast kernel must give its
// numbers bit for bit. Every deck of decks/ and tests/decks/ (the good ones), shortened,
// runs with the reference kernel and with the fast kernel with AVX2 on and off and with
// 1, 2 and 3 threads; at every frame the point table and the history rows (as the program
// writes them) and the bits of every point, cell and node array must be equal.
#include "../lpfdm.hpp"
#include "common.hpp"

#include <doctest/doctest.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#if defined(_OPENMP)
#include <omp.h>
#endif

using namespace lpfdm;

namespace {

// What a run left at each frame: the program's text output, and one digest per array.
struct Trace {
    std::string tables;                                        // point frames and history rows
    std::vector<std::pair<std::string, std::uint64_t>> arrays; // "step name" -> FNV-1a of the bits
};

std::uint64_t fnv1a(const void* data, std::size_t n) {
    std::uint64_t h = 1469598103934665603ull;
    const auto* b = static_cast<const unsigned char*>(data);
    for (std::size_t i = 0; i < n; ++i) { h ^= b[i]; h *= 1099511628211ull; }
    return h;
}
template <class V>
void digest(Trace& t, long step, const char* name, const V& v) {
    t.arrays.push_back({std::to_string(step) + " " + name, fnv1a(v.data(), v.size() * sizeof(v[0]))});
}

std::string read_all(std::FILE* f) {
    std::string s;
    std::rewind(f);
    char buf[65536];
    for (std::size_t n; (n = std::fread(buf, 1, sizeof buf, f)) > 0;) s.append(buf, n);
    return s;
}

void set_threads([[maybe_unused]] int n) {
#if defined(_OPENMP)
    omp_set_num_threads(n);
#endif
}

// steps steps of the scene with kernel k on `threads` threads; a frame every `every` steps.
// prepare: called on the new simulation before the first step (points moved, say).
Trace run(const Scene& s, Kernel k, int threads, long steps, long every, const UserModel& user = nullptr, int user_mat = 0,
          const std::function<void(Simulation&)>& prepare = nullptr) {
    set_threads(threads);
    Simulation sim(s, k);
    if (user) sim.set_user_model(user_mat, user);
    if (prepare) prepare(sim);
    Trace t;
    std::FILE* f = std::tmpfile();
    REQUIRE(f);
    write_history_header(f, sim, "deck");
    bool first = true;
    for (long n = 1; n <= steps; ++n) {
        sim.step();
        write_history_row(f, sim);
        if (n % every != 0 && n != steps) continue;
        write_points_frame(f, sim, first);
        first = false;
        const Points& p = sim.points();
        digest(t, n, "x", p.x); digest(t, n, "y", p.y);
        digest(t, n, "sxx", p.sxx); digest(t, n, "syy", p.syy); digest(t, n, "sxy", p.sxy); digest(t, n, "szz", p.szz);
        digest(t, n, "vol", p.vol); digest(t, n, "cell", p.cell); digest(t, n, "id", p.id);
        digest(t, n, "plastic_shear", p.plastic_shear); digest(t, n, "yielded", p.yielded); digest(t, n, "plastic_work", p.plastic_work);
        digest(t, n, "flip_ux", p.flip_ux); digest(t, n, "flip_uy", p.flip_uy);
        digest(t, n, "du_x", sim.du_x()); digest(t, n, "du_y", sim.du_y());
        digest(t, n, "force_x", sim.force_x()); digest(t, n, "force_y", sim.force_y());
        digest(t, n, "node_mass", sim.node_mass()); digest(t, n, "cell_mass", sim.cell_mass()); digest(t, n, "cell_volume", sim.cell_volume());
        const double scalars[] = {sim.kinetic_energy(), sim.mass_inside(), sim.mass_outflow(), sim.max_du(), sim.reaction_x(), sim.reaction_y()};
        t.arrays.push_back({std::to_string(n) + " scalars", fnv1a(scalars, sizeof scalars)});
        if (!sim.healthy()) break;  // where the program stops
    }
    t.tables = read_all(f);
    std::fclose(f);
    set_threads(1);
    return t;
}

// The first frame and array at which two traces differ ("" if none).
std::string first_difference(const Trace& a, const Trace& b) {
    for (std::size_t i = 0; i < std::min(a.arrays.size(), b.arrays.size()); ++i)
        if (a.arrays[i] != b.arrays[i]) return "step and array " + a.arrays[i].first;
    if (a.arrays.size() != b.arrays.size()) return "number of frames";
    if (a.tables != b.tables) {
        std::size_t i = 0;
        while (i < a.tables.size() && i < b.tables.size() && a.tables[i] == b.tables[i]) ++i;
        return "tables, at byte " + std::to_string(i);
    }
    return "";
}

// Every fast kernel (AVX2 on and off, 1, 2 and 3 threads; the consult's four lanes where
// it would take eight) against the reference.
void compare_kernels(const std::string& name, const Scene& s, long steps, const UserModel& user = nullptr, int user_mat = 0,
                     const std::function<void(Simulation&)>& prepare = nullptr) {
    const long every = std::max(1L, steps / 4);
    const Trace ref = run(s, Kernel::Reference, 1, steps, every, user, user_mat, prepare);
    CHECK_MESSAGE(ref.tables.size() > 100, name);
    for (Kernel k : {Kernel::Fast, Kernel::Scalar})
        for (int threads : {1, 2, 3}) {
            const Trace fast = run(s, k, threads, steps, every, user, user_mat, prepare);
            const std::string diff = first_difference(ref, fast);
            INFO(name << ": kernel " << std::string(kernel_name(k)) << ", " << threads << " thread(s), " << steps << " steps: differs at " << diff);
            CHECK(diff.empty());
        }
}

// The decks a user can run: decks/*.deck and the good decks of tests/decks.
std::vector<std::filesystem::path> runnable_decks() {
    std::vector<std::filesystem::path> v;
    for (const char* dir : {"decks", "tests/decks"})
        for (const auto& e : std::filesystem::directory_iterator(dir)) {
            const std::string f = e.path().filename().string();
            if (e.path().extension() != ".deck" || f.rfind("bad_", 0) == 0 || f.rfind("fuzz_", 0) == 0) continue;
            v.push_back(e.path());
        }
    std::sort(v.begin(), v.end());
    return v;
}

// Steps for a scene of n points: about 3e5 particle-steps a run (3e4 with small_runs(),
// under the sanitizers), at least 12 and at most the deck's.
long steps_for(const Scene& s) {
    const double n = std::max(1.0, count_points(s)), budget = small_runs() ? 3e4 : 3e5;
    return std::min(s.steps, std::max(12L, long(budget / n)));
}

}  // namespace

// Every deck with at most (big: more than) 20 000 points.
void compare_decks(bool big) {
    const auto decks = runnable_decks();
    REQUIRE(decks.size() >= 20);
    int ran = 0;
    for (const auto& path : decks) {
        Scene s;
        const Diagnostics d = read_deck(path.string(), s);
        REQUIRE_MESSAGE(d.empty(), path.string());
        REQUIRE_MESSAGE(validate(s).empty(), path.string());
        if ((count_points(s) > 20000) != big) continue;
        compare_kernels(path.string(), s, steps_for(s));
        ++ran;
    }
    CHECK(ran >= (big ? 3 : 15));
}

TEST_CASE("every deck: the fast kernels (AVX2 on and off, 1, 2 and 3 threads) give the reference cycle's bits at every frame") {
    compare_decks(false);
}

// The benchmark and threads decks: 65 000 to 131 000 points, the ones whose lattice loops
// and point pass run by threads. Not in the sanitizer build (minutes there).
TEST_CASE("every deck of more than 20 000 points: the same bits [slow]") {
    compare_decks(true);
}

TEST_CASE("the options no shipped deck uses, on a flowing column and a hopper: the same bits") {
    for (const char* deck : {"decks/verify_collapse.deck", "decks/verify_hopper.deck"}) {
        Scene base;
        REQUIRE(read_deck(deck, base).empty());
        const long steps = std::max(40L, steps_for(base));
        for (Motion m : {Motion::Centre, Motion::Bilinear}) {
            Scene s = base;
            s.motion = m;
            compare_kernels(std::string(deck) + (m == Motion::Centre ? " MOTION CENTRE" : " MOTION BILINEAR"), s, steps);
            s.advect = Advect::Points;
            compare_kernels(std::string(deck) + " ADVECT POINTS", s, steps);
        }
        Scene h = base;
        h.hourglass = 0.05;
        compare_kernels(std::string(deck) + " HOURGLASS", h, steps);
        h.mapping = Mapping::Smooth;  // (the fast kernel once added the two nodal terms in the other order)
        compare_kernels(std::string(deck) + " HOURGLASS MAPPING SMOOTH", h, steps);
        h.advect = Advect::Flip;
        compare_kernels(std::string(deck) + " HOURGLASS MAPPING SMOOTH ADVECT FLIP", h, steps);
        Scene m = base;
        m.mapping = Mapping::Smooth;
        compare_kernels(std::string(deck) + " MAPPING SMOOTH", m, steps);
        m.reorder = 3;
        compare_kernels(std::string(deck) + " MAPPING SMOOTH REORDER 3", m, steps);
        m.reorder = base.reorder;
        m.motion = Motion::Centre;  // the fast kernel's other SMOOTH pass (no lanes for the motion)
        compare_kernels(std::string(deck) + " MAPPING SMOOTH MOTION CENTRE", m, steps);
        Scene r = base;  // the storage sorted by cell every step
        r.reorder = 1;
        compare_kernels(std::string(deck) + " REORDER 1", r, steps);
    }
}

// MAPPING SMOOTH with ADVECT FLIP on scenes of 12 000 to 18 000 points (the lattice made
// twice as fine), so that the points' passes run by threads: walls driving a Mohr-Coulomb
// specimen (psc.deck), a softening, scattered cliff failing (cliff.deck), a hopper the
// points leave through (verify_hopper.deck), a cliff shaken (quake_cliff.deck, SHAKE from
// the first step: START moved to 0); and a column on an absorbing base (ABSORB).
TEST_CASE("MAPPING SMOOTH with ADVECT FLIP, walls, softening, points leaving, SHAKE and ABSORB, by threads: the same bits") {
    for (const char* deck : {"decks/psc.deck", "decks/cliff.deck", "decks/verify_hopper.deck", "decks/quake_cliff.deck", "decks/quake_column_compliant.deck"}) {
        Scene s;
        REQUIRE(read_deck(deck, s).empty());
        s.mapping = Mapping::Smooth;
        s.advect = Advect::Flip;
        refine(s, 2);
        for (auto& sh : s.shakes) sh.start = 0;
        REQUIRE_MESSAGE(validate(s).empty(), std::string(deck));
        const bool column = std::string(deck) == "decks/quake_column_compliant.deck";  // (2 560 points: one thread)
        if (!column) REQUIRE(count_points(s) > 4096);  // the threaded passes' threshold (Simulation::serial)
        compare_kernels(std::string(deck) + " MAPPING SMOOTH ADVECT FLIP, twice as fine", s, steps_for(s));
    }
}

// SHIFT (Simulation::shift_points) with ABOVE=1, so that its passes start at the first
// crowding: a tall collapse three times as fine (4 608 points: the threaded passes, whose
// boxes the moved points must stay inside; fixed edges) with the paper's cycle and with
// ADVECT FLIP, a hopper (points leaving), and psc.deck's walls under ADVECT FLIP twice as
// fine. Each run moves points (checked; the hopper's first pass comes after 200 steps, past
// the sanitizer build's shorter run), and every kernel moves the same ones.
TEST_CASE("SHIFT with the paper's cycle and with ADVECT FLIP, fixed edges, walls, points leaving, by threads: the same bits") {
    struct Case { const char* deck; bool flip; int refine; double y1; long steps; };
    for (const Case& c : {Case{"decks/verify_collapse.deck", false, 3, 2, 60}, Case{"decks/verify_collapse.deck", true, 3, 2, 60},
                          Case{"decks/verify_hopper.deck", false, 1, 0, 300}, Case{"decks/psc.deck", true, 2, 0, 60}}) {
        Scene s;
        REQUIRE(read_deck(c.deck, s).empty());
        s.outputs.clear();
        if (c.y1 > 0) s.clusters[0].box.y1 = c.y1;
        if (c.flip) { s.mapping = Mapping::Smooth; s.advect = Advect::Flip; }
        refine(s, c.refine);
        s.shift = true;
        s.shift_above = 1;
        REQUIRE_MESSAGE(validate(s).empty(), std::string(c.deck));
        REQUIRE(count_points(s) > 4096);  // the threaded passes' threshold (Simulation::serial)
        const long steps = small_runs() ? c.steps / 4 : c.steps;
        const std::string name = std::string(c.deck) + (c.flip ? " ADVECT FLIP" : "") + " SHIFT ABOVE=1, refined " + std::to_string(c.refine);
        if (steps >= 200 || c.refine > 1) {
            Simulation moving(s);
            for (long n = 0; n < steps; ++n) moving.step();
            CHECK_MESSAGE(moving.shifted() > 0, name);
        }
        compare_kernels(name, s, steps);
    }
}

// SHIFT's guard (shift_relief), after every step: the tall collapse of the case above with
// its lower metre squeezed to 0.4 of its height before the first step (ten points in
// cells made with four), so that the guard moves points from the first step on.
TEST_CASE("SHIFT's guard with the paper's cycle and with ADVECT FLIP, by threads: the same bits") {
    for (const bool flip : {false, true}) {
        Scene s;
        REQUIRE(read_deck("decks/verify_collapse.deck", s).empty());
        s.outputs.clear();
        s.clusters[0].box.y1 = 2;
        if (flip) { s.mapping = Mapping::Smooth; s.advect = Advect::Flip; }
        refine(s, 3);
        s.shift = true;
        REQUIRE(validate(s).empty());
        REQUIRE(count_points(s) > 4096);
        auto squeeze = [](Simulation& sim) {
            Points& p = sim.points();
            for (std::size_t k = 0; k < p.size(); ++k)
                if (p.y[k] < 1) { p.y[k] *= 0.4; p.cell[k] = sim.cell_holding(p.x[k], p.y[k]); }
            sim.map_to_lattice();
        };
        const long steps = small_runs() ? 8 : 30;
        const std::string name = std::string("decks/verify_collapse.deck") + (flip ? " ADVECT FLIP" : "") + " SHIFT, squeezed";
        Simulation moving(s);
        squeeze(moving);
        moving.step();
        CHECK_MESSAGE(moving.shifted() > 0, name);  // the guard, at the first step (a pass comes at the tenth)
        compare_kernels(name, s, steps, nullptr, 0, squeeze);
    }
}

// DAMPING WINDOW (eq. 14 about each node's mean increment, damped_increment): the means
// are advanced where eq. 13 is, in the reference cycle over the whole lattice, in the fast
// kernel over its boxes and by threads, with ADVECT FLIP in its own step 5, and read again
// by the nodes beyond the material (follow_material), an embedded wall's pair of lines and
// the energy account. psc.deck (a wall embedded in a cap on a Mohr-Coulomb specimen) with
// each mapping, twice as fine (12 800 points: the threaded passes).
TEST_CASE("DAMPING WINDOW with each mapping and ADVECT FLIP, an embedded wall, by threads: the same bits") {
    for (int mode = 0; mode < 3; ++mode) {
        Scene s;
        REQUIRE(read_deck("decks/psc.deck", s).empty());
        s.damping_window = 1e-3;
        if (mode > 0) s.mapping = Mapping::Smooth;
        if (mode > 1) s.advect = Advect::Flip;
        refine(s, 2);
        REQUIRE(validate(s).empty());
        REQUIRE(count_points(s) > 4096);
        compare_kernels(std::string("decks/psc.deck DAMPING WINDOW=1E-3") + (mode == 0 ? "" : mode == 1 ? " MAPPING SMOOTH" : " MAPPING SMOOTH ADVECT FLIP") + ", twice as fine", s, steps_for(s));
    }
}

// Modes: read once from the scene; the kernel asked for runs it, and where its point pass
// goes one point at a time or on one thread, the reason is named.
TEST_CASE("modes: what a scene switches on, and which kernel runs it, and why") {
    Scene s;
    REQUIRE(read_deck("decks/verify_collapse.deck", s).empty());
    const Modes d = modes_of(s, Kernel::Fast);
    CHECK(d.mapping == Mapping::Paper);
    CHECK(d.motion == Motion::Centre);  // the default rule with the paper's mapping
    CHECK(d.advect == Advect::Eq12);
    CHECK(!d.hourglass);
    CHECK(!d.dynamic);
    CHECK(d.plastic);  // a Mohr-Coulomb material
    CHECK(d.kernel == Kernel::Fast);
    CHECK(std::string(d.points_why).empty());  // the AVX2 point loop runs the default modes
    CHECK(!d.shake);
    s.mapping = Mapping::Smooth;
    CHECK(std::string(modes_of(s, Kernel::Fast).points_why) == "MAPPING SMOOTH: its sums a point at a time (a cell's side by side), the rest four points at a time");
    CHECK(std::string(modes_of(s, Kernel::Reference).points_why).empty());
    s.motion = Motion::Centre;  // smooth_lanes follows MOTION BILINEAR, SMOOTH's default
    CHECK(std::string(modes_of(s, Kernel::Fast).points_why) == "MAPPING SMOOTH with MOTION PAPER or CENTRE: AVX2 for the Mohr-Coulomb consult only");
    s.motion = Motion::Default;
    s.hourglass = 0.05;
    CHECK(modes_of(s, Kernel::Scalar).motion == Motion::Bilinear);  // SMOOTH's default rule
    CHECK(modes_of(s, Kernel::Scalar).hourglass);
    s.advect = Advect::Flip;
    for (Kernel k : {Kernel::Fast, Kernel::Scalar, Kernel::Reference}) {  // every kernel runs every mode
        CHECK(modes_of(s, k).kernel == k);
        CHECK(Simulation(s, k).kernel() == k);
    }
    CHECK(std::string(modes_of(s, Kernel::Fast).points_why) == "MAPPING SMOOTH: its sums a point at a time (a cell's side by side), the rest four points at a time");
    Scene m;  // MOTION PAPER, and a user's model: named too
    REQUIRE(read_deck("decks/verify_collapse.deck", m).empty());
    m.motion = Motion::Paper;
    CHECK(std::string(modes_of(m, Kernel::Fast).points_why) == "MOTION PAPER has no AVX2 point loop");
    Simulation sim(m);
    CHECK(!sim.modes().user);
    sim.set_user_model(m.materials.front().id, [](const StrainIncrement&, Stress&, PointState&) {});
    CHECK(sim.modes().user);
    CHECK(std::string(sim.modes().threads_why) == "a user's model runs on one thread");
}

// The AVX2 loop takes a scene with a Mohr-Coulomb material four points at a time across
// cells; a point that stops on a fixed edge or a wall's face, one that leaves the lattice,
// four of two materials, a four that lands in a cell of another thread's chunk, and the
// last one to three points of a chunk take their own ways there, which the shortened
// decks rarely reach. A block of soil with an elastic one in it (7 671 points: the
// threads take chunks of it) thrown up (gravity 2000 m/s^2) against a rough ceiling, a
// smooth side and a wall coming up, and out through the open part of the top edge; a
// lattice 98 cells wide (a cell's row, c / 98, is where a careless division rounds
// wrong). And a row of seven points pressed into a smooth side on a rough floor, whose
// last three (the loop's last points) cross the side and stop on it.
const char* const kThrownBlock =
    "GRID     98 40 0.05\n"
    "MATERIAL 1 MOHR E=1E7 NU=0.3 RHO=2000 PHI=30 C=200 SOFTEN=0.5 SCATTER=0.2\n"
    "MATERIAL 2 ELASTIC E=2E7 NU=0.25 RHO=2500\n"
    "CLUSTER  1  0 0.8  4 2  PPC=2\n"
    "CLUSTER  2  0.5 0.8  3.5 1.2  PPC=2\n"
    "CLUSTER  1  3.85 1.95  4 2  PPC=1\n"
    "FIX X    0 0  0 2\n"
    "FIX XY   1.5 2  4.9 2\n"
    "WALL 1   3.0 0.8 3.6 0.8  0 2 SMOOTH\n"
    "GRAVITY  0 2000\n"
    "SEED     3\n"
    "STEP     2.5E-4 120\n"
    "END\n";

TEST_CASE("a flowing block against fixed edges, a wall and the lattice's edge: the same bits") {
    Scene s;
    REQUIRE(read_deck_text(kThrownBlock, "thrown.deck", s).empty());
    compare_kernels("thrown.deck", s, 120);
    Simulation sim(s);
    for (int n = 0; n < 120; ++n) sim.step();
    CHECK(sim.mass_outflow() > 0.2 * (sim.mass_inside() + sim.mass_outflow()));  // the lattice's edge was crossed
    const std::string row =
        "GRID     20 4 0.1\n"
        "MATERIAL 1 MOHR E=1E7 NU=0.3 RHO=2000 PHI=30 C=200\n"
        "CLUSTER  1  0 0  0.7 0.1  PPC=1\n"
        "FIX XY   0 0  2 0\n"
        "FIX X    0.7 0  0.7 0.4\n"
        "FIX X    0 0  0 0.4\n"
        "GRAVITY  3000 -1000\n"
        "STEP     2.5E-4 200\n"
        "END\n";
    Scene r;
    REQUIRE(read_deck_text(row, "row.deck", r).empty());
    compare_kernels("row.deck", r, 200);
    // Each move the side's nodes hold is counted (held(): the point moved with the cell's
    // bilinear field, not its affine one; compare_kernels compares every point's bits in
    // every kernel): the three that would cross it, at least. None is clamped (parked()).
    Simulation rs(r);
    for (int n = 0; n < 200; ++n) rs.step();
    MESSAGE("row.deck: " << rs.held() << " moves held by the side's nodes, " << rs.parked() << " clamped, in 200 steps");
    CHECK(rs.held() >= 3);
    CHECK(rs.parked() == 0);
}

// MAPPING SMOOTH's lanes (smooth_lanes, squares_lanes, smear_lanes, flip_sums_lanes) at
// the lattice's far edges: a lattice full to its top and right edges, Mohr-Coulomb beside
// elastic, thrown up and right so that points leave through both (the squares' clamps at
// the last row and column, points leaving within a block of four); and an elastic scene
// under ADVECT FLIP large enough for threads (drop.deck at 40 cells across), where the
// blocks run without the Mohr-Coulomb consult.
const char* const kFullBox =
    "GRID     36 30 0.1\n"
    "MATERIAL 1 MOHR E=1E7 NU=0.3 RHO=2000 PHI=30 C=0 PSI=0\n"
    "MATERIAL 2 ELASTIC E=2E7 NU=0.3 RHO=2000\n"
    "CLUSTER  1  0 0  3.6 1.5  PPC=2\n"
    "CLUSTER  2  0 1.5  1.8 3.0  PPC=2\n"
    "CLUSTER  1  1.8 1.5  3.6 3.0  PPC=2\n"
    "FIX XY   0 0  3.6 0\n"
    "FIX X    0 0  0 3.0\n"
    "GRAVITY  30 20\n"
    "DAMPING  0\n"
    "STEP     4E-4 200\n"
    "END\n";

TEST_CASE("MAPPING SMOOTH, with and without ADVECT FLIP, at the lattice's top and right edges, and an elastic FLIP scene by threads: the same bits") {
    for (const char* mode : {"MAPPING SMOOTH", "MAPPING SMOOTH ADVECT FLIP"}) {
        Scene s;
        REQUIRE(read_deck_text(kFullBox, "fullbox.deck", s).empty());
        s.mapping = Mapping::Smooth;
        if (std::string(mode).find("FLIP") != std::string::npos) s.advect = Advect::Flip;
        REQUIRE(validate(s).empty());
        compare_kernels(std::string("fullbox.deck ") + mode, s, 200);
        Simulation sim(s);
        for (int n = 0; n < 200; ++n) sim.step();
        CHECK(sim.mass_outflow() > 0.01 * (sim.mass_inside() + sim.mass_outflow()));  // points left through the far edges
    }
    Scene d;
    REQUIRE(read_deck("decks/drop.deck", d).empty());
    refine(d, 5);  // 6 400 points
    REQUIRE(validate(d).empty());
    compare_kernels("decks/drop.deck, five times as fine", d, 300);
}

TEST_CASE("a user constitutive model (eq. 6's signature) runs the same in every kernel") {
    Scene s;
    REQUIRE(read_deck("decks/verify_collapse.deck", s).empty());
    // A material of its own: elastic up to a cap on the shear stress (a crude Tresca).
    const int mat = s.materials.front().id;
    const double G = s.materials.front().shear(), lam = s.materials.front().bulk() - 2 * G / 3;
    auto tresca = [G, lam](const StrainIncrement& e, Stress& st, PointState& ps) {
        st.xx += (lam + 2 * G) * e.xx + lam * e.yy;
        st.yy += lam * e.xx + (lam + 2 * G) * e.yy;
        st.zz += lam * (e.xx + e.yy);
        st.xy += G * e.gamma();
        const double cap = 2e3;
        if (std::fabs(st.xy) > cap) { ps.plastic_shear += (std::fabs(st.xy) - cap) / G; ps.yielded = true; st.xy = st.xy > 0 ? cap : -cap; }
    };
    compare_kernels("user model", s, std::max(40L, steps_for(s)), tresca, mat);
    // Beside a Mohr-Coulomb material, a user's model sends the AVX2 loop's blocks run by run.
    Scene b;
    REQUIRE(read_deck_text(kThrownBlock, "thrown.deck", b).empty());
    const Material& m2 = b.materials.back();
    const double G2 = m2.shear(), lam2 = m2.bulk() - 2 * G2 / 3;
    auto hooke = [G2, lam2](const StrainIncrement& e, Stress& st, PointState&) {
        st.xx += (lam2 + 2 * G2) * e.xx + lam2 * e.yy;
        st.yy += lam2 * e.xx + (lam2 + 2 * G2) * e.yy;
        st.zz += lam2 * (e.xx + e.yy);
        st.xy += G2 * e.gamma();
    };
    compare_kernels("user model beside Mohr-Coulomb", b, 120, hooke, m2.id);
}

// Pore water with every mapping and transfer, on 5 184 points (so that threads take the
// points' passes): a saturated Mohr-Coulomb block under a water table, starting
// geostatic, pressed by a wall and loaded by a traction, draining through its top and to a
// reservoir that falls from above it, softening, scattered, points leaving the lattice.
// Also UNDRAINED (no flow, no drain), whose pass takes the points in one band pass. 35 runs
// of 5 184 points: 120 steps, 30 with small_runs() (the reservoir starts falling at step 25).
TEST_CASE("WATER, DRAIN, LOAD, RESERVOIR and GEOSTATIC with MAPPING PAPER, SMOOTH and SMOOTH + FLIP, and UNDRAINED, by threads: the same bits") {
    const char* text = R"(GRID 64 32 0.125
MATERIAL 1 MOHR E=5E7 NU=0.3 RHO=2000 PHI=30 C=2000 SOFTEN=0.5 SCATTER=0.2 POROSITY=0.4 PERM=1E-4
CLUSTER 1 5 0 8 3 PPC=3
FIX XY 0 0 8 0
WALL 1 5.5 3 6.5 3 0 -2
WATER KW=1E7 TABLE=2
DRAIN 5 3 8 3
LOAD 7 3 8 3 TY=-2E4
RESERVOIR 3.5 TO=1 START=0.01 OVER=0.02
GEOSTATIC
GRAVITY 0 -98.1
SEED 7
STEP 4E-4 120
)";
    // modes 3 and 4: UNDRAINED (no flow, no DRAIN), with either mapping
    const char* names[] = {"PAPER", "SMOOTH", "SMOOTH + FLIP", "UNDRAINED PAPER", "UNDRAINED SMOOTH"};
    for (int mode = 0; mode < 5; ++mode) {
        Scene s;
        REQUIRE(read_deck_text(text, "water.deck", s).empty());
        if (mode == 1 || mode == 2 || mode == 4) s.mapping = Mapping::Smooth;
        if (mode == 2) s.advect = Advect::Flip;
        if (mode > 2) { s.water.undrained = true; s.drains.clear(); }
        REQUIRE(validate(s).empty());
        REQUIRE(count_points(s) > 4096);
        compare_kernels(std::string("water ") + names[mode], s, small_runs() ? 30 : 120);
    }
}
