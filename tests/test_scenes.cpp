// Whole scenes from decks/ with known outcomes: vertical cuts below and above the
// critical height (design notes §5), and the cliff of the paper's Fig. 5.
#include <doctest/doctest.h>

#include <cmath>
#include <vector>

#include "../lpfdm.hpp"

using namespace lpfdm;

namespace {

struct Motion {
    double max_disp = 0, front0 = 0, front = 0;
};

// Runs a deck and reports the largest point displacement and the toe's advance.
Motion run(const char* deck, double damping = -1, long steps = 0) {
    Scene s;
    const Diagnostics d = read_deck(deck, s);
    REQUIRE(d.empty());
    if (damping >= 0) s.damping = damping;
    if (steps > 0) s.steps = steps;
    Simulation sim(s);
    const Points& p = sim.points();
    std::vector<double> x0(p.x.begin(), p.x.end()), y0(p.y.begin(), p.y.end());
    Motion m;
    for (double x : p.x) m.front0 = std::max(m.front0, x);
    for (long n = 0; n < s.steps; ++n) {
        sim.step();
        REQUIRE(sim.healthy());
    }
    for (std::size_t k = 0; k < p.size(); ++k) {
        const std::size_t id = std::size_t(p.id[k]);
        m.max_disp = std::max(m.max_disp, std::hypot(p.x[k] - x0[id], p.y[k] - y0[id]));
        m.front = std::max(m.front, p.x[k]);
    }
    CHECK(sim.mass_inside() + sim.mass_outflow() == sim.mass_initial());
    return m;
}

}  // namespace

TEST_CASE("a vertical cut at 0.4 of the critical height stands") {
    const Motion m = run("decks/cut_low.deck");
    MESSAGE("1.5 m cut: largest displacement " << m.max_disp << " m");
    CHECK(m.max_disp < 0.02 * 0.5);  // far below L = 0.5 m: elastic settlement only
}

TEST_CASE("a vertical cut at 2.1 times the critical height collapses [slow]") {
    const Motion free = run("decks/cut_high.deck", 0.0, 8000);  // 4 s without damping
    MESSAGE("8 m cut, no damping, 4 s: run-out " << free.front - free.front0 << " m");
    CHECK(free.front - free.front0 > 4.0);
    const Motion damped = run("decks/cut_high.deck");  // the deck: damping 0.8, 8 s
    MESSAGE("8 m cut, damping 0.8, 8 s: run-out " << damped.front - damped.front0 << " m");
    CHECK(damped.front - damped.front0 > 1.0);
}
