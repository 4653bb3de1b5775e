// "No allocation inside the time step", checked: the test binaries count every call of
// the global operator new while a window is open, and step real scenes inside it.
#include <doctest/doctest.h>

#include <atomic>
#include <string>
#include <vector>

#if defined(_OPENMP)
#include <omp.h>
#endif

#include "../lpfdm.hpp"
#include "common.hpp"

// The counter lives in tests/alloc_counter.cpp, which replaces the global operator new.
namespace alloc_counter {
extern std::atomic<bool> counting;
extern std::atomic<long> news;
}  // namespace alloc_counter
namespace {
std::atomic<bool>& g_counting = alloc_counter::counting;
std::atomic<long>& g_news = alloc_counter::news;
}  // namespace

using namespace lpfdm;

namespace {

// Allocations made by `steps` calls of step() (and, with profile, of the profiled step).
long news_in_steps(const Scene& s, long steps, bool profile = false, Kernel kernel = Kernel::Fast) {
    Simulation sim(s, kernel);
    sim.set_profiling(profile);
    g_news = 0;
    g_counting = true;
    for (long n = 0; n < steps; ++n) sim.step();
    g_counting = false;
    REQUIRE(sim.healthy());
    return g_news.load();
}

Scene deck(const char* path, long steps) {
    Scene s;
    const Diagnostics d = read_deck(path, s);
    for (const auto& e : d) MESSAGE(e.str());
    REQUIRE(d.empty());
    s.outputs.clear();
    s.steps = steps;
    return s;
}

}  // namespace

TEST_CASE("the counter sees an allocation (the test can fail)") {
    g_news = 0;
    g_counting = true;
    std::vector<double>* v = new std::vector<double>(100);
    g_counting = false;
    delete v;
    CHECK(g_news.load() >= 2);  // the vector object and its buffer
}

TEST_CASE("no allocation inside the time step, from the first step on") {
    // Each scene exercises one path of the step: elastic under gravity, Mohr-Coulomb with
    // scatter and softening (the cliff), walls (compression test), points leaving the
    // lattice (trapdoor), the alternative motions, the hourglass control and MAPPING SMOOTH;
    // ground motion in x and y with absorbing edges released at START (good_quake); pore
    // water's flow and drains, and a LOAD (consolidation).
    struct Case { const char* deck; long steps; };
    for (const Case c : {Case{"decks/column.deck", 300}, Case{"decks/cliff.deck", 300}, Case{"decks/psc.deck", 300},
                         Case{"decks/trapdoor.deck", 300}, Case{"decks/cut_high.deck", 300}, Case{"tests/decks/good_quake.deck", 200},
                         Case{"decks/consolidation.deck", 300}}) {
        const Scene s = deck(c.deck, c.steps);
        const long n = news_in_steps(s, c.steps);
        INFO(std::string(c.deck));
        CHECK(n == 0);
        CHECK(news_in_steps(s, 20, true) == 0);  // profiled steps too
        CHECK(news_in_steps(s, 50, false, Kernel::Reference) == 0);  // the reference cycle too
    }
    Scene s = deck("decks/cliff.deck", 200);
    s.motion = Motion::Centre;
    s.hourglass = 0.05;
    CHECK(news_in_steps(s, 200) == 0);
    s.motion = Motion::Bilinear;
    CHECK(news_in_steps(s, 200) == 0);
    s.advect = Advect::Points;  // increments carried by the points
    CHECK(news_in_steps(s, 200) == 0);
    CHECK(news_in_steps(s, 20, true) == 0);
    s.advect = Advect::Eq12;
    s.mapping = Mapping::Smooth;  // points as squares, over every cell they overlap
    CHECK(news_in_steps(s, 200) == 0);
    CHECK(news_in_steps(s, 50, false, Kernel::Reference) == 0);
    s.advect = Advect::Flip;  // the points keep their increments
    CHECK(news_in_steps(s, 100) == 0);
    CHECK(news_in_steps(s, 20, true) == 0);
    CHECK(news_in_steps(s, 50, false, Kernel::Reference) == 0);
    s.advect = Advect::Eq12;
    s.mapping = Mapping::Paper;
    s.reorder = 3;  // the points' storage sorted by cell every third step
    CHECK(news_in_steps(s, 200) == 0);
    CHECK(news_in_steps(s, 20, true) == 0);
    CHECK(news_in_steps(s, 50, false, Kernel::Reference) == 0);
    // ADVECT FLIP with walls (the compression test's embedded cap: flip_transfer's list of
    // held nodes, sorted) and with the ground's motion and absorbing edges (absorb_work)
    for (const Case c : {Case{"decks/psc.deck", 100}, Case{"tests/decks/good_quake.deck", 100}}) {
        Scene f = deck(c.deck, c.steps);
        f.mapping = Mapping::Smooth;
        f.advect = Advect::Flip;
        INFO(std::string(c.deck));
        CHECK(news_in_steps(f, c.steps) == 0);
        CHECK(news_in_steps(f, 20, false, Kernel::Reference) == 0);
    }
    // SHIFT from the first crowding (ABOVE=1; its sub-cells are made at set-up): a tall
    // collapse three times as fine under the paper's cycle and psc.deck under ADVECT FLIP
    // both move points from step 10 on (checked)
    for (const bool flip : {false, true}) {
        Scene f = deck(flip ? "decks/psc.deck" : "decks/verify_collapse.deck", 60);
        if (flip) { f.mapping = Mapping::Smooth; f.advect = Advect::Flip; }
        else { f.clusters[0].box.y1 = 2; refine(f, 3); }
        f.shift = true;
        f.shift_above = 1;
        INFO(std::string(flip ? "psc.deck, FLIP, SHIFT" : "collapse, SHIFT"));
        Simulation moving(f);
        for (int k = 0; k < 60; ++k) moving.step();
        CHECK(moving.shifted() > 0);
        CHECK(news_in_steps(f, 60) == 0);
        CHECK(news_in_steps(f, 20, false, Kernel::Reference) == 0);
    }
}

TEST_CASE("no allocation inside the time step when points leave the lattice") {
    Scene s;
    s.mx = 8; s.my = 8; s.cell_m = 0.25;
    s.materials.push_back(Material::elastic(1, 2e7, 0.25, 2000));
    s.clusters.push_back({1, {0.5, 0.25, 1.5, 1.25}, 2, {}});
    s.gravity_y = -9.81; s.dt_s = 1e-3;
    Simulation sim(s);
    g_news = 0;
    g_counting = true;
    long n = 0;
    while (sim.points().size() > 0 && n < 5000) { sim.step(); ++n; }
    g_counting = false;
    CHECK(sim.points().size() == 0);  // every point left through the open bottom
    CHECK(sim.mass_outflow() == sim.mass_initial());
    CHECK(g_news.load() == 0);
}

#if defined(_OPENMP)
TEST_CASE("no allocation inside the time step with two threads, once the thread team exists") {
    // The OpenMP runtime builds its thread team at the first parallel region; after that
    // a step allocates nothing. The Mohr-Coulomb benchmark block has more points than the
    // parallel threshold (4096) and a lattice large enough for the parallel node loops.
    const int before = omp_get_max_threads();
    omp_set_num_threads(2);
    Scene s = deck("decks/bench_mohr.deck", 20);
    for (const Cycle& cycle : kCycles) {
        cycle.apply(s);
        s.reorder = cycle.paper() ? 5 : 0;
        Simulation sim(s);
        sim.step();
        g_news = 0;
        g_counting = true;
        for (int k = 0; k < 20; ++k) sim.step();
        g_counting = false;
        CHECK(sim.points().size() > 4096);
        CHECK(g_news.load() == 0);
    }
    omp_set_num_threads(before);
}
#endif
