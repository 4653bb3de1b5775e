// Coverage-guided fuzzing of the deck reader (libFuzzer): any byte string goes to
// lpfdm::read_deck_text; a deck it accepts, if small, becomes a Simulation that runs a
// few steps and writes a frame and a history row. Nothing may crash, trip a sanitizer
// or run long. Build and run with `make fuzz` (tools/fuzz.sh).
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <string>

#define LPFDM_IMPLEMENTATION  // the fuzzing program's one unit
#include "../lpfdm.hpp"

namespace {

// Caps so that one input cannot run long: lattice cells, points, steps.
constexpr double kMaxCells = 20000, kMaxPoints = 20000;
constexpr long kMaxSteps = 4;

std::FILE* sink() {
    static std::FILE* f = std::fopen("/dev/null", "wb");
    return f;
}

void run_small(lpfdm::Scene& s) {
    if (double(s.mx) * double(s.my) > kMaxCells) return;
    if (lpfdm::count_points(s) > kMaxPoints) return;
    lpfdm::Simulation sim(s);
    const long steps = s.steps < kMaxSteps ? s.steps : kMaxSteps;
    for (long n = 0; n < steps; ++n) {
        sim.step();
        if (!sim.healthy()) {
            (void)sim.first_nonfinite_point();  // the program's guard path
            break;
        }
    }
    if (std::FILE* f = sink()) {
        lpfdm::write_points_header(f, sim, "fuzz.deck");
        lpfdm::write_points_frame(f, sim, false);
        lpfdm::write_history_header(f, sim, "fuzz.deck");
        lpfdm::write_history_row(f, sim);
        lpfdm::write_vtu(f, sim, {}, {}, false);
        lpfdm::write_vtu(f, sim, {}, {}, true);
        lpfdm::write_state(f, sim, 0);
    }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::string text(reinterpret_cast<const char*>(data), size);
    lpfdm::Scene s;
    const lpfdm::Diagnostics d = lpfdm::read_deck_text(text, "fuzz.deck", s);
    for (const auto& m : d) (void)m.str();  // every message must be printable
    if (!d.empty()) return 0;
    // The program's checks before a run: the point count (it scans the lattice up to 5e7
    // cells; kept cheap here, the bound above that is exercised), the memory estimate,
    // and the same deck refined twice (--refine 2).
    auto countable = [](const lpfdm::Scene& sc) {
        const double cells = double(sc.mx) * double(sc.my);
        return cells <= 1e6 || cells > 5e7;
    };
    if (countable(s)) (void)lpfdm::estimate_bytes(s, lpfdm::count_points(s));
    lpfdm::Scene r = s;
    if (r.mx <= 500'000 && r.my <= 500'000) {
        lpfdm::refine(r, 2);
        if (lpfdm::validate(r).empty() && countable(r)) (void)lpfdm::count_points(r);
    }
    run_small(s);
    return 0;
}
