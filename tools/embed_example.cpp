// embed_example.cpp -- lpfdm used as a library: a scene built in code (no deck), stepped,
// read back and checked against a closed-form answer; and a constitutive model of one's
// own, plugged in through Simulation::set_user_model without editing lpfdm.hpp.
//
// Build and run (the header needs only the C++17 standard library with LPFDM_NO_IO):
//   g++ -std=c++17 -O2 -DLPFDM_NO_IO -I. tools/embed_example.cpp -o embed_example && ./embed_example
// Exit status 0 when every check passes, 1 otherwise.
#define LPFDM_IMPLEMENTATION  // the kernel's definitions: in one file of a program, the others include it alone
#include "lpfdm.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace {

// The confined elastic column of decks/column.deck: 2 m x 12 m, L = 0.5 m, rough base,
// smooth sides, brought to rest by local damping (eq. 13-14).
lpfdm::Scene column() {
    lpfdm::Scene s;
    s.mx = 4; s.my = 26; s.cell_m = 0.5;
    s.materials.push_back(lpfdm::Material::elastic(1, 2e7, 0.25, 2000));
    s.clusters.push_back({1, {0, 0, 2, 12}, 2, {}});            // material, box [m], 2x2 points per cell
    s.fixes.push_back({lpfdm::kFixX, {0, 0, 0, 13}, {}});        // smooth sides
    s.fixes.push_back({lpfdm::kFixX, {2, 0, 2, 13}, {}});
    s.fixes.push_back({lpfdm::kFixX | lpfdm::kFixY, {0, 0, 2, 0}, {}});  // rough base
    s.gravity_y = -9.81; s.damping = 0.8; s.dt_s = 1e-3; s.steps = 6000;
    return s;
}

// Plane-strain Hooke's law written by hand: eq. 6 with M(d_eps, sigma) = sigma + D d_eps.
// The kernel has already turned the old stress by the Jaumann rotation (eq. 5f).
struct MyElastic {
    double lambda, G;  // Lame constants
    void operator()(const lpfdm::StrainIncrement& d, lpfdm::Stress& s, lpfdm::PointState&) const {
        const double dv = d.xx + d.yy;  // volumetric strain increment
        s.xx += lambda * dv + 2 * G * d.xx;
        s.yy += lambda * dv + 2 * G * d.yy;
        s.xy += G * d.gamma();          // eq. 5e
        s.zz += lambda * dv;            // plane strain: d_eps_zz = 0
    }
};

int failures = 0;
void check(bool ok, const char* what) {
    std::printf("%s  %s\n", ok ? "ok  " : "FAIL", what);
    failures += !ok;
}

}  // namespace

int main() {
    const lpfdm::Scene s = column();
    const lpfdm::Diagnostics problems = lpfdm::validate(s);  // empty when the scene can run
    for (const auto& d : problems) std::printf("%s\n", d.str().c_str());
    if (!problems.empty()) return 1;

    const lpfdm::Material& m = s.materials[0];
    const double E = m.E, nu = m.nu, rho = m.rho, g = -s.gravity_y, H = 12;
    lpfdm::Simulation builtin(s), mine(s);
    mine.set_user_model(1, MyElastic{E * nu / ((1 + nu) * (1 - 2 * nu)), E / (2 * (1 + nu))});
    for (long n = 0; n < s.steps; ++n) { builtin.step(); mine.step(); }

    // Read back: stress of the lowest row of points, and the top of the column.
    const lpfdm::Points& p = builtin.points();
    const double ybase = *std::min_element(p.y.begin(), p.y.end());
    double syy = 0, ytop = 0;
    int nbase = 0;
    for (std::size_t k = 0; k < p.size(); ++k) {
        if (p.y[k] < ybase + 0.1) { syy += p.syy[k]; ++nbase; }
        ytop = std::max(ytop, p.y[k]);
    }
    syy /= nbase;
    const double syy_ref = -rho * g * (H - ybase);
    const double M = E * (1 - nu) / ((1 + nu) * (1 - 2 * nu));
    const double settle = (H - 0.125) - ytop, settle_ref = rho * g * H * H / (2 * M);  // top points start at H - L/4
    std::printf("after %ld steps (t = %g s), %zu points, kinetic energy %.3g J/m\n", builtin.step_count(), builtin.time(), p.size(),
                builtin.kinetic_energy());
    std::printf("base stress    %10.1f Pa   reference -rho g (H - y) %10.1f Pa   (%+.2f %%)\n", syy, syy_ref, 100 * (syy / syy_ref - 1));
    std::printf("top settlement %10.5f m    reference gamma H^2 / 2M %10.5f m    (%+.2f %%)\n", settle, settle_ref, 100 * (settle / settle_ref - 1));
    check(std::fabs(syy / syy_ref - 1) < 0.03, "base stress within 3 % of -rho g (H - y)");
    check(std::fabs(settle / settle_ref - 1) < 0.02, "top settlement within 2 % of gamma H^2 / 2M");
    check(builtin.mass_inside() == builtin.mass_initial(), "mass kept exactly");

    // The hand-written model must reproduce the built-in elastic one, point by point.
    const lpfdm::Points& q = mine.points();
    double scale = 0, dmax = 0, xmax = 0;
    for (std::size_t k = 0; k < p.size(); ++k) {
        scale = std::max(scale, std::fabs(p.syy[k]));
        dmax = std::max({dmax, std::fabs(p.sxx[k] - q.sxx[k]), std::fabs(p.syy[k] - q.syy[k]), std::fabs(p.sxy[k] - q.sxy[k]),
                         std::fabs(p.szz[k] - q.szz[k])});
        xmax = std::max({xmax, std::fabs(p.x[k] - q.x[k]), std::fabs(p.y[k] - q.y[k])});
    }
    std::printf("user model vs built-in: largest difference %.2g of the stress scale, %.2g m in position (rounding)\n", dmax / scale, xmax);
    check(q.size() == p.size() && dmax <= 1e-6 * scale && xmax <= 1e-6 * s.cell_m, "hand-written elastic model reproduces the built-in one");
    std::printf("%s\n", failures ? "embed example: FAILED" : "embed example: all checks passed");
    return failures ? 1 : 0;
}
