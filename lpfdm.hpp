// lpfdm.hpp — Lagrangian Particle Finite Difference Method (Konagai & Johansson, 2001)
// for 2D plane-strain large deformations of soil. One header, C++17.
//
// WHAT IT IS
//   Unconnected material points carry every Lagrangian quantity (stress, volume,
//   strength, plastic strain) across a fixed square lattice of cells of side L. Each step
//   runs FLAC's explicit cycle on the lattice, moves the points with it, and resets the
//   lattice: no global matrix, no iteration. Equation numbers (// eq. 5a) are the paper's.
//
// USE (stb's single-file pattern)
//   In exactly one .cpp file of the program:
//     #define LPFDM_IMPLEMENTATION
//     #include "lpfdm.hpp"
//   In every other file, only the declarations:
//     #include "lpfdm.hpp"                      // C++17 only (+ fmt for the deck reader)
//     lpfdm::Scene s;                           // build in code, or lpfdm::read_deck("x.deck", s)
//     s.mx = 40; s.my = 24; s.cell_m = 0.5;     //   lattice: 40 x 24 cells of 0.5 m
//     s.materials.push_back(lpfdm::Material::elastic(1, 2e7, 0.25, 2000));
//     s.clusters.push_back({1, {0, 0, 20, 12}, 2});     // mat, box [m], 2x2 points/cell
//     s.fixes.push_back({lpfdm::kFixX | lpfdm::kFixY, {0, 0, 20, 0}});
//     s.gravity_y = -9.81; s.damping = 0.8; s.dt_s = 1e-3; s.steps = 6000;
//     auto diags = lpfdm::validate(s);          // empty when the scene can run
//     auto warns = lpfdm::warnings(s);          // legal but probably wrong (units, angles)
//     lpfdm::Simulation sim(s);                 // points made here; nothing allocated later
//     for (long n = 0; n < s.steps; ++n) sim.step();
//     const lpfdm::Points& p = sim.points();    // p.x[k], p.syy[k], ... (structure of arrays)
//   Your own eq. 6: sim.set_user_model(mat_id, f), f(const StrainIncrement&, Stress&, PointState&).
//   A slope's factor of safety: lpfdm::factor_of_safety(s).F (strength reduction, --fos).
//   A program without the implementation unit fails to link, naming
//   define_LPFDM_IMPLEMENTATION_in_one_unit.
//
// CONFIGURATION (define before including, alike in every unit of a program)
//   LPFDM_IMPLEMENTATION  this unit holds the definitions (exactly one unit)
//   LPFDM_HEADER_ONLY     every unit holds them, inline; implies LPFDM_IMPLEMENTATION
//   LPFDM_INTERNALS       a unit sees the implementation's inline equations and helpers
//                         (namespace detail) as well, not its out-of-line definitions: the
//                         unit tests, which link against one LPFDM_IMPLEMENTATION unit
//   LPFDM_NO_IO           leave out the deck reader and the writers (then no fmt is needed)
//   LPFDM_NO_WIDE         leave out the AVX2 version (so does any build with -mfma or -mavx512f)
//
// KERNELS (chosen once: Simulation sim(s, lpfdm::Kernel::Reference))
//   Reference  Simulation::step_reference: the plain cycle, every cell, point and node,
//              one value at a time, one thread. Read this one: it is the definition.
//   Fast       (default) the same cycle on the occupied cells only, by threads (OpenMP,
//              -fopenmp) and four values per AVX2 register when the processor has it.
//   Scalar     Fast without AVX2.
//   All give the same numbers, bit for bit, on every deck (tests/test_reference.cpp).
//   What a scene switches on (mapping, motion rule, transfer, hourglass control,
//   earthquakes) is read once into Simulation::modes(); every kernel runs every mode.
//
// THE PAPER'S EQUATIONS, AND THE FUNCTION THAT COMPUTES EACH
//   eq. 5a-5d  cell strain increments from nodal increments     cell_strain (MAPPING SMOOTH:
//                                                               smooth_strain, axis_shape)
//   eq. 5e-5f  shear strain, rotation; the Jaumann rotation     StrainIncrement::gamma, theta,
//                                                               jaumann_rotation, rotate_stress
//   eq. 6      a point's stress: the model, once a step          Simulation::consult_model
//              elastic (Hooke, plane strain)                    elastic_change, elastic_increment,
//                                                               elastic_trial
//              Mohr-Coulomb return (FLAC's, closed form)         mohr_coulomb_return,
//                                                               Simulation::mohr_consult
//              each point's strength (scatter, softening)       Simulation::strength_of
//   eq. 7a-7b  point motion with its cell                        move_point_paper (MOTION CENTRE:
//                                                               move_point_centre, BILINEAR: _bilinear)
//   eq. 7      cell mass; eq. 8 cell stress sum V sigma          CellSums::add
//   eq. 8      the division by L^2 (capped, see the equations)  smear_weight
//   eq. 9      nodal force, as the transpose of eq. 5            add_cell_force
//   eq. 10     lumped node mass, gravity                         Simulation::reference_nodal_forces
//   eq. 11-14  the increment with local damping                  damped_increment
//   eq. 12     compensation of the carried increment             compensate_increment,
//                                                               Simulation::strain_at
//   the cycle  steps 1-5 in order                                Simulation::step_reference
//   boundaries fixed directions, moving walls (section 3)        Simulation::impose_supports
//   earthquakes ground motion (SHAKE), absorbing edges (ABSORB)   Simulation::ground_step,
//              (not in the paper)                               dynamics_begin, absorb_increments, absorb_work
//
// THE REFERENCE CYCLE, one step (Simulation::step_reference; its section reads top to bottom)
//   1 reference_cell_strains  eq. 5 in every cell with mass, and its rotation
//   2 reference_points        per point: eq. 6, volume, eq. 7a/7b, then eq. 7-8 into
//                             the cell it lands in; points leaving the lattice leave
//   3 reference_nodal_forces  eq. 8, the transpose of eq. 5, eq. 10
//   4 reference_compensate    eq. 12 (or ADVECT POINTS; ADVECT FLIP's transfer ends step 2)
//   5 reference_integrate     eq. 13-14, fixed nodes, moving walls, kinetic energy
//   then, every REORDER steps, reorder_points: the points' storage sorted by cell (not
//   physics: the order in which the sums of eq. 7-8 take the points; every kernel sorts)
//
// SECTIONS OF THIS FILE, in order: the public declarations (the scene, the deck's keys,
// points, Simulation); then, with LPFDM_IMPLEMENTATION: the equations; materials; lattice
// and points; boundaries (fixed nodes, walls); the energy account; the reference cycle;
// one section per option (MAPPING SMOOTH, ADVECT FLIP, ADVECT POINTS, HOURGLASS,
// earthquakes); the fast kernel and its AVX2 lanes; restart; the factor of safety by
// strength reduction (lpfdm --fos); checks; the deck reader, writers and state files. Each section builds on those before it; where the reference
// cycle hands a step to an option it calls that option's section (named at the call),
// and it never calls the fast kernel. Where the paper is open, the choice made and its
// reason head the section it concerns. Decks, options and output: decks/README.md.
#ifndef LPFDM_HPP
#define LPFDM_HPP

#include <algorithm>
#include <atomic>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <functional>
#include <limits>
#include <string>
#include <vector>


// LPFDM_OMP: an OpenMP pragma where the build has OpenMP (-fopenmp), else nothing.
#if defined(_OPENMP)
#define LPFDM_STR_(...) #__VA_ARGS__
#define LPFDM_OMP(...) _Pragma(LPFDM_STR_(__VA_ARGS__))
#else
#define LPFDM_OMP(...)
#endif
#if defined(__GNUC__)
#define LPFDM_INLINE __attribute__((always_inline))
#else
#define LPFDM_INLINE
#endif
// LPFDM_WIDE: on x86-64 with GCC or Clang, the point loop (with the paper's motion rule;
// MAPPING SMOOTH's and ADVECT FLIP's passes over the points and their sums) and the regular
// lattice phases (eq. 5, the nodal forces, eq. 13-14) have a second version built for
// AVX2, taken when the processor has it: four points, cells or nodes per register instead
// of one or two, the same numbers bit for bit. Define LPFDM_NO_WIDE to
// leave it out. A build with fused multiply-add (-mfma, -march=native, x86-64-v3) leaves
// it out too: the compiler fuses a*b - c*d on either product, not always alike in the two
// versions, so they would no longer agree bit for bit. So does a build for AVX-512
// (-mavx512f), which brings fused multiply-add to GCC without defining __FMA__.
#if defined(__GNUC__) && defined(__x86_64__) && !defined(__FMA__) && !defined(__AVX512F__) && !defined(LPFDM_NO_WIDE)
#define LPFDM_WIDE 1
#else
#define LPFDM_WIDE 0
#endif
// LPFDM_DEF: how the definitions of the public functions are made. By default (stb's
// pattern) they are defined once, in the unit that defines LPFDM_IMPLEMENTATION; with
// LPFDM_HEADER_ONLY (which implies it) every unit that includes the header holds them,
// inline, and compiles the kernel again (no unit need be chosen).
#if defined(LPFDM_HEADER_ONLY)
#define LPFDM_DEF inline
#ifndef LPFDM_IMPLEMENTATION
#define LPFDM_IMPLEMENTATION
#endif
#else
#define LPFDM_DEF
#endif

// ======================================================================================
// PUBLIC DECLARATIONS
//
// What a program that embeds the kernel uses: the scene, the points, a Simulation and
// the functions that read, check and write them. Definitions follow in the
// implementation (LPFDM_IMPLEMENTATION).
// ======================================================================================
namespace lpfdm {

inline constexpr const char* kVersion = "0.1.0";

// ---------------------------------------------------------------- types ---

// Where a card or field came from: printed as file:line:column (GNU style).
struct Pos {
    std::string file;
    int line = 0, col = 0;
};

struct Diagnostic {
    Pos pos;
    std::string message;
    bool warning = false;  // legal but probably wrong (warnings()); an error stops the run
    std::string str() const {
        std::string where = pos.file.empty() ? std::string("scene") : pos.file;
        if (pos.line > 0) where += ":" + std::to_string(pos.line) + ":" + std::to_string(pos.col);
        return where + (warning ? ": warning: " : ": error: ") + message;
    }
};
using Diagnostics = std::vector<Diagnostic>;

// Axis-aligned box in metres; a degenerate box selects a line of nodes.
struct Box {
    double x0 = 0, y0 = 0, x1 = 0, y1 = 0;
};

// Strain increments of one cell, eq. 5a-5d (d_eps_xy = d(du_x)/dy, d_eps_yx = d(du_y)/dx).
struct StrainIncrement {
    double xx = 0, yy = 0, xy = 0, yx = 0;
    double gamma() const { return xy + yx; }          // eq. 5e
    double theta() const { return 0.5 * (yx - xy); }  // eq. 5f
};

// Point stress, tension positive, plane strain (zz carried).
struct Stress {
    double xx = 0, yy = 0, xy = 0, zz = 0;
};

enum class Model : std::uint8_t { Elastic, MohrCoulomb, User };

// Isotropic elastic constants and, for MohrCoulomb, the strength (mean values).
struct Material {
    int id = 0;
    Model model = Model::Elastic;
    double E = 0, nu = 0, rho = 0;               // Pa, -, kg/m^3
    double phi_deg = 0, c = 0, psi_deg = 0;      // friction, cohesion [Pa], dilation
    double tension = -1;                         // tension limit [Pa]; < 0: the apex c/tan(phi)
    double soften = 0;                           // fraction of c lost at first yield
    double scatter = 0;                          // coefficient of variation of c and phi
    // Saturated (WATER): porosity n (0: dry) and hydraulic conductivity k [m/s]; RHO is then
    // the saturated density and E, NU, PHI, C, PSI are drained (effective-stress) values.
    double porosity = 0, perm = 0;
    Pos pos;                                     // of the card, for messages

    static Material elastic(int id, double E, double nu, double rho) {
        Material m;
        m.id = id; m.E = E; m.nu = nu; m.rho = rho;
        return m;
    }
    static Material mohr(int id, double E, double nu, double rho, double phi_deg, double c,
                         double psi_deg = 0, double tension = -1, double soften = 0,
                         double scatter = 0) {
        Material m = elastic(id, E, nu, rho);
        m.model = Model::MohrCoulomb;
        m.phi_deg = phi_deg; m.c = c; m.psi_deg = psi_deg; m.tension = tension;
        m.soften = soften; m.scatter = scatter;
        return m;
    }
    double bulk() const { return E / (3 * (1 - 2 * nu)); }
    double shear() const { return E / (2 * (1 + nu)); }
    double p_wave_speed() const { return std::sqrt((bulk() + 4 * shear() / 3) / rho); }
};

struct Cluster {
    int mat = 0;
    Box box;
    int ppc = 2;  // points per cell along each axis
    Pos pos;
    // POLYGON: the vertices x1 y1 x2 y2 ... [m], in either orientation, closing by itself
    // (empty: the box). A cell belongs to it when its centre lies inside or within L/1000
    // of an edge in x and in y, as a box's centre may lie L/1000 past the box.
    std::vector<double> polygon = {};
    std::vector<Pos> polygon_pos = {};  // each coordinate's field in the deck (for messages)
    // FILL=POINTS: of the PPC x PPC points of each cell, those whose own positions lie in
    // the box or polygon (by the rule above, on the lattice of the points, spacing L / PPC),
    // so that a face across the lattice is not a staircase of whole cells; FILL=CELLS (the
    // default): all of them, in the cells whose centres lie in it (detail::made_points).
    bool fill_points = false;
};

enum : int { kFixX = 1, kFixY = 2 };

struct Fix {
    int dirs = kFixX | kFixY;
    Box box;
    Pos pos;
};

struct Wall {
    int id = 0;
    Box box;
    double vx = 0, vy = 0;  // m/s
    Pos pos;
    // Rough (false): bonded, every node of the wall driven in x and y. Smooth: a line of
    // nodes driven across the line only (normal contact; the material slides along it).
    bool smooth = false;
};

// Ground motion (SHAKE, an earthquake): an acceleration record a(t) in one direction. Its
// time 0 falls at model time START; before it and after its last sample the ground's
// acceleration is zero, between samples linear. Rigid (the default): every node fixed in
// that direction moves with the ground, by the increments of the record integrated as eq.
// 13 integrates a node (v += a dt, du = v dt). COMPLIANT: the fixed nodes stay; the record
// enters through the lattice's bottom edge as a stress wave (Joyner and Chen: a traction
// 2 rho c v_in, c = c_s across x and c_p along y, on a base that absorbs as ABSORB BOTTOM).
// BASELINE takes a linear trend c0 + c1 t off the record's acceleration so that the
// ground's velocity and displacement, integrated step by step, end at zero (to rounding).
struct Shake {
    int dir = 1;                     // kFixX or kFixY
    std::string file;                // the motion file, as the card names it
    std::vector<double> t, a;        // the record: time [s] (increasing, >= 0), acceleration [m/s^2]
    double scale = 1;                // SCALE: the record times this
    double start = 0;                // START: the model time of the record's time 0 [s]
    double damping = -1;             // DAMPING: local damping alpha from START on (< 0: the deck's)
    bool compliant = false, baseline = false;
    Pos pos;
};
// WATER: the pore water of the saturated materials (POROSITY > 0). Its bulk modulus KW
// [Pa] and density RHOW [kg/m^3]; TABLE: a phreatic level y [m] below which the pore
// pressure starts hydrostatic, rho_w |g_y| (TABLE - y) (no TABLE: it starts at 0);
// UNDRAINED: no flow, the pore pressure changes with the volume only.
struct Water {
    bool on = false;
    double kw = 2.2e9, rhow = 1000;
    double table = -std::numeric_limits<double>::infinity();  // -inf: no TABLE
    bool undrained = false;
    Pos pos;
};
// DRAIN x0 y0 x1 y1: every cell edge whose two nodes lie in the box holds the hydrostatic
// pore pressure (0 without TABLE); water leaves or enters there freely.
struct Drain {
    Box box;
    Pos pos;
};
// LOAD x0 y0 x1 y1 TX= TY=: a traction [Pa] on the nodes of a line (a degenerate box),
// each node its share of the line's length, carried by the material point nearest it.
struct Load {
    Box box;
    double tx = 0, ty = 0;
    Pos pos;
};

// RESERVOIR level [TO=y] [START=t] [OVER=s]: free water outside the material, its surface
// at y = level [m]; from model time START it is lowered (or raised) linearly to TO over
// OVER seconds (0: at once). Below it, the material's free surfaces (cell edges to empty
// cells inside the lattice) take its hydrostatic pressure and, for saturated material,
// are drained to it.
struct Reservoir {
    bool on = false;
    double level = 0;
    double to = -std::numeric_limits<double>::infinity();  // -inf: stays at level
    double start = 0, over = 0;
    Pos pos;
    double at(double t) const {
        if (!(to > -std::numeric_limits<double>::infinity()) || t <= start) return level;
        if (t >= start + over) return to;
        return level + (to - level) * (t - start) / over;
    }
};

// Edges of the lattice (ABSORB).
enum : int { kBottom = 1, kTop = 2, kLeft = 4, kRight = 8 };

// TRACK x y: the history follows the point nearest (x, y) at step 0.
struct Track {
    double x = 0, y = 0;  // [m]
    Pos pos;
};

struct Output {
    enum Kind { Points, History, Vtu, State } kind = Points;
    std::string file;  // VTU: the series' name (NAME.pvd, NAME_<step>.vtu)
    long every = 0;  // 0: points, VTU: first and last frame only; history: every step; state: the last step only
    bool binary = false;  // VTU: the arrays as appended raw binary (else ASCII)
    bool nodes = false;   // VTU: the lattice's nodes too, as a second series (NAME_nodes.pvd)
    Pos pos;
};

// How points move with the lattice: the paper's eq. 7a/7b (affine about node [1] of the
// cell), the same affine map about the cell centre with the mean of the four nodal
// increments (mirror-symmetric), or the bilinear interpolation of the four increments
// (as in MPM). All three agree for any affine increment field; they differ by the part
// of the cell's increments that is not affine, which eq. 7a/7b takes from node [1] alone,
// so that a mirror-symmetric scene drifts to one side. Default (no MOTION card): CENTRE
// with the paper's mapping, BILINEAR with MAPPING SMOOTH (whose strain is the gradient of
// the bilinear field: the motion and the strain then agree). Both are mirror-symmetric.
enum class Motion : std::uint8_t { Paper, Centre, Bilinear, Default };

// How the nodal increments follow the material from one step to the next: eq. 12's
// correction of each node's own increment (the paper), or carried by the points: each
// point takes its cell's increment field (its eq. 7 motion and the cell's eq. 5 strain)
// and brings it, with its mass, to the nodes of the cell it lands in. Or ADVECT FLIP
// (MAPPING SMOOTH only): every point keeps an increment of its own, which the lattice's
// change reaches each step, and the lattice is made from the points' increments anew: no
// energy is lost or made in the transfer (Simulation::flip_transfer, flip_return).
enum class Advect : std::uint8_t { Eq12, Points, Flip };

// How a point takes part in the lattice: the paper's (all of it in the cell holding its
// centre: its strain, rotation and motion are that cell's, its mass and V sigma go to that
// cell, and each jumps when the point crosses a cell edge), or SMOOTH: the point is the
// square it stood for when made (side L / PPC) and takes part in each cell in proportion
// to the area of the square inside it, as GIMP's point domains do: strain, rotation and
// motion are the weighted sums of the cells' (each cell's strain and motion taken at the
// centre of the point's part in it), mass and V sigma are shared out by the same weights. Everything a
// point contributes then varies continuously as it crosses an edge. A point inside one
// cell sees the gradient at its own centre, not at the cell's (with one point per cell
// they are the same).
enum class Mapping : std::uint8_t { Paper, Smooth };

// Everything a run needs; built by the deck reader or in code. Zero means unset.
struct Scene {
    Motion motion = Motion::Default;
    Mapping mapping = Mapping::Paper;
    Pos mapping_pos;
    Advect advect = Advect::Eq12;
    double hourglass = 0;               // kappa: viscous control of eq. 5's zero-energy mode (0: off)
    // SHIFT [RATE=r] [ABOVE=a]: points moved apart where they crowd (Simulation::shift_points).
    bool shift = false;
    double shift_rate = 0.1, shift_above = 1.25;
    Pos shift_pos;
    std::string title;
    int mx = 0, my = 0;
    double cell_m = 0;                  // L
    std::vector<Material> materials;
    std::vector<Cluster> clusters;
    std::vector<Fix> fixes;
    std::vector<Wall> walls;
    std::vector<Shake> shakes;          // SHAKE cards (at most one per direction)
    int absorb = 0;                     // ABSORB: edges with viscous dashpots (kBottom | kTop | kLeft | kRight)
    Pos absorb_pos;
    int outflow = 0;                    // OUTFLOW: edges the material is meant to leave through (no warning)
    Pos outflow_pos;
    double gravity_x = 0, gravity_y = 0;
    double damping = 0;                 // alpha of eq. 14
    double damping_window = 0;          // DAMPING WINDOW=t: eq. 14 about each node's mean increment over t seconds (0: about rest)
    std::uint64_t seed = 1;
    long reorder = 50;                  // REORDER n: the points' storage sorted by cell every n steps (0: never)
    double dt_s = 0;
    long steps = 0;
    std::vector<Output> outputs;
    std::vector<Track> tracks;
    Water water;                        // WATER (water.on: the card is given)
    std::vector<Drain> drains;
    std::vector<Load> loads;
    Reservoir reservoir;                // RESERVOIR (reservoir.on: the card is given)
    // GEOSTATIC [K0=k]: the points start in geostatic equilibrium (Simulation::geostatic);
    // k0 < 0: each material's nu / (1 - nu).
    bool geostatic = false;
    double k0 = -1;
    Pos geostatic_pos;
    Pos grid_pos, step_pos, damping_pos, end_pos, advect_pos;

    const Material* material(int id) const {
        for (const auto& m : materials) if (m.id == id) return &m;
        return nullptr;
    }
};

// --------------------------------------------------------- the deck's keys ---

// The numbers of the deck language in one table: every card's positional fields (in card
// order) and NAME=value parameters, with what they mean, their range and where they go in
// a Scene. The deck reader reads fields by it, validate() checks ranges by it, --set
// finds and checks a key by it, and --help lists it (a test checks that decks/README.md
// names every card and key). Words (FIX X|Y|XY, OUTPUT POINTS file, ...) are the reader's.
struct DeckKey {
    const char* card;     // GRID, MATERIAL, ...
    const char* name;     // --set CARD.NAME, and NAME= for a parameter
    const char* what;     // the field as messages name it, with units
    const char* subject;  // range messages say "<subject> must ..."
    bool param;           // a NAME=value parameter (else a positional field)
    bool required;        // a parameter that must be given (fields always are)
    bool settable;        // --set may change it (not ids)
    double lo, hi;        // accepted range ...
    bool lo_open, hi_open, whole;  // ... its ends open or closed; whole numbers only
    const char* unit;     // after the range in messages
    double fallback;      // a parameter not given; a value equal to it is always accepted
    int models;           // MATERIAL: the models that take it (bit 1 ELASTIC, bit 2 MOHR)
    double (*get)(const Scene&, std::size_t);
    void (*set)(Scene&, std::size_t, double);  // the index: among the cards of its kind, in deck order
};

#define LPFDM_AT(list, member) \
    [](const Scene& s, std::size_t i) { return double(s.list[i].member); }, \
    [](Scene& s, std::size_t i, double v) { s.list[i].member = static_cast<decltype(s.list[i].member)>(v); }
#define LPFDM_OF(member) \
    [](const Scene& s, std::size_t) { return double(s.member); }, \
    [](Scene& s, std::size_t, double v) { s.member = static_cast<decltype(s.member)>(v); }
inline constexpr double kHuge = std::numeric_limits<double>::infinity();
inline constexpr int kElastic = 1, kMohr = 2, kBoth = 3;
inline const DeckKey kDeckKeys[] = {
    // card        name       what                   subject              param  req    set    lo      hi          lo_o   hi_o   whole  unit        fallback models
    {"GRID",      "MX",      "mx (cells in x)",     "mx (cells in x)",   false, true,  true,  1,      1e6,        false, false, true,  "",         0,   0, LPFDM_OF(mx)},
    {"GRID",      "MY",      "my (cells in y)",     "my (cells in y)",   false, true,  true,  1,      1e6,        false, false, true,  "",         0,   0, LPFDM_OF(my)},
    {"GRID",      "L",       "L (cell size, m)",    "the cell size L",   false, true,  true,  0,      kHuge,      true,  true,  false, "",         0,   0, LPFDM_OF(cell_m)},
    {"MATERIAL",  "ID",      "material id",         "material id",       false, true,  false, 1,      65535,      false, false, true,  "",         0,   0, LPFDM_AT(materials, id)},
    {"MATERIAL",  "E",       "Young's modulus, Pa", "E",                 true,  true,  true,  0,      kHuge,      true,  true,  false, "",         0,   kBoth, LPFDM_AT(materials, E)},
    {"MATERIAL",  "NU",      "Poisson's ratio",     "NU",                true,  true,  true,  -1,     0.5,        true,  true,  false, "",         0,   kBoth, LPFDM_AT(materials, nu)},
    {"MATERIAL",  "RHO",     "density, kg/m^3",     "RHO",               true,  true,  true,  0,      kHuge,      true,  true,  false, "",         0,   kBoth, LPFDM_AT(materials, rho)},
    {"MATERIAL",  "PHI",     "friction angle, deg", "PHI",               true,  true,  true,  0,      90,         false, true,  false, " degrees", 0,   kMohr, LPFDM_AT(materials, phi_deg)},
    {"MATERIAL",  "C",       "cohesion, Pa",        "C",                 true,  true,  true,  0,      kHuge,      false, true,  false, "",         0,   kMohr, LPFDM_AT(materials, c)},
    {"MATERIAL",  "PSI",     "dilation angle, deg (at most PHI)", "PSI", true,  false, true,  0,      90,         false, true,  false, "",         0,   kMohr, LPFDM_AT(materials, psi_deg)},
    {"MATERIAL",  "TENSION", "tension limit, Pa (default: the apex c / tan phi)", "TENSION", true, false, true, 0, kHuge, false, true, false, "", -1, kMohr, LPFDM_AT(materials, tension)},
    {"MATERIAL",  "SOFTEN",  "fraction of c lost at first yield", "SOFTEN", true, false, true, 0,    1,          false, false, false, "",         0,   kMohr, LPFDM_AT(materials, soften)},
    {"MATERIAL",  "SCATTER", "coefficient of variation of c and phi", "SCATTER", true, false, true, 0, 0.5,      false, false, false, "",         0,   kMohr, LPFDM_AT(materials, scatter)},
    {"MATERIAL",  "POROSITY", "porosity (saturated: needs WATER)", "POROSITY", true, false, true, 0, 1,          true,  true,  false, "",         0,   kBoth, LPFDM_AT(materials, porosity)},
    {"MATERIAL",  "PERM",    "hydraulic conductivity, m/s", "PERM",      true,  false, true,  0,      kHuge,      false, true,  false, "",         0,   kBoth, LPFDM_AT(materials, perm)},
    {"CLUSTER",   "MAT",     "material id",         "material id",       false, true,  true,  1,      65535,      false, false, true,  "",         0,   0, LPFDM_AT(clusters, mat)},
    {"CLUSTER",   "X0",      "x0",                  "x0",                false, true,  true,  -kHuge, kHuge,      true,  true,  false, "",         0,   0, LPFDM_AT(clusters, box.x0)},
    {"CLUSTER",   "Y0",      "y0",                  "y0",                false, true,  true,  -kHuge, kHuge,      true,  true,  false, "",         0,   0, LPFDM_AT(clusters, box.y0)},
    {"CLUSTER",   "X1",      "x1",                  "x1",                false, true,  true,  -kHuge, kHuge,      true,  true,  false, "",         0,   0, LPFDM_AT(clusters, box.x1)},
    {"CLUSTER",   "Y1",      "y1",                  "y1",                false, true,  true,  -kHuge, kHuge,      true,  true,  false, "",         0,   0, LPFDM_AT(clusters, box.y1)},
    {"CLUSTER",   "PPC",     "points per cell along each axis", "PPC",   true,  false, true,  1,      32,         false, false, true,  "",         2,   0, LPFDM_AT(clusters, ppc)},
    {"FIX",       "X0",      "x0",                  "x0",                false, true,  true,  -kHuge, kHuge,      true,  true,  false, "",         0,   0, LPFDM_AT(fixes, box.x0)},
    {"FIX",       "Y0",      "y0",                  "y0",                false, true,  true,  -kHuge, kHuge,      true,  true,  false, "",         0,   0, LPFDM_AT(fixes, box.y0)},
    {"FIX",       "X1",      "x1",                  "x1",                false, true,  true,  -kHuge, kHuge,      true,  true,  false, "",         0,   0, LPFDM_AT(fixes, box.x1)},
    {"FIX",       "Y1",      "y1",                  "y1",                false, true,  true,  -kHuge, kHuge,      true,  true,  false, "",         0,   0, LPFDM_AT(fixes, box.y1)},
    {"WALL",      "ID",      "wall id",             "wall id",           false, true,  false, 1,      65535,      false, false, true,  "",         0,   0, LPFDM_AT(walls, id)},
    {"WALL",      "X0",      "x0",                  "x0",                false, true,  true,  -kHuge, kHuge,      true,  true,  false, "",         0,   0, LPFDM_AT(walls, box.x0)},
    {"WALL",      "Y0",      "y0",                  "y0",                false, true,  true,  -kHuge, kHuge,      true,  true,  false, "",         0,   0, LPFDM_AT(walls, box.y0)},
    {"WALL",      "X1",      "x1",                  "x1",                false, true,  true,  -kHuge, kHuge,      true,  true,  false, "",         0,   0, LPFDM_AT(walls, box.x1)},
    {"WALL",      "Y1",      "y1",                  "y1",                false, true,  true,  -kHuge, kHuge,      true,  true,  false, "",         0,   0, LPFDM_AT(walls, box.y1)},
    {"WALL",      "VX",      "VX (m/s)",            "VX",                false, true,  true,  -kHuge, kHuge,      true,  true,  false, "",         0,   0, LPFDM_AT(walls, vx)},
    {"WALL",      "VY",      "VY (m/s)",            "VY",                false, true,  true,  -kHuge, kHuge,      true,  true,  false, "",         0,   0, LPFDM_AT(walls, vy)},
    {"GRAVITY",   "GX",      "gx (m/s^2)",          "gx",                false, true,  true,  -kHuge, kHuge,      true,  true,  false, "",         0,   0, LPFDM_OF(gravity_x)},
    {"GRAVITY",   "GY",      "gy (m/s^2)",          "gy",                false, true,  true,  -kHuge, kHuge,      true,  true,  false, "",         0,   0, LPFDM_OF(gravity_y)},
    {"DAMPING",   "ALPHA",   "alpha",               "DAMPING alpha",     false, true,  true,  0,      1,          false, true,  false, "",         0,   0, LPFDM_OF(damping)},
    {"DAMPING",   "WINDOW",  "time over which each node's mean increment is taken, s (0: eq. 14 about rest)", "WINDOW", true, false, true, 0, kHuge, false, true, false, "", 0, 0, LPFDM_OF(damping_window)},
    {"HOURGLASS", "KAPPA",   "kappa",               "HOURGLASS kappa",   false, true,  true,  0,      1,          false, false, false, "",         0,   0, LPFDM_OF(hourglass)},
    {"SHIFT",     "RATE",    "how far a point moves every 10 steps, in L/2, per unit of the fill's change across L/2", "RATE", true, false, true, 0, 1, true, false, false, "", 0.1, 0, LPFDM_OF(shift_rate)},
    {"SHIFT",     "ABOVE",   "the fill (the points' area over the lattice's) above which they move apart", "ABOVE", true, false, true, 1, 4, false, false, false, "", 1.25, 0, LPFDM_OF(shift_above)},
    {"SEED",      "N",       "seed",                "seed",              false, true,  true,  0,      9007199254740992.0, false, false, true, "", 0,   0, LPFDM_OF(seed)},
    {"REORDER",   "N",       "steps between sorts of the points", "REORDER n",        false, true,  true,  0,      1e9,        false, false, true,  "",         0,   0, LPFDM_OF(reorder)},
    {"STEP",      "DT",      "dt (s)",              "the time step dt",  false, true,  true,  0,      kHuge,      true,  true,  false, "",         0,   0, LPFDM_OF(dt_s)},
    {"STEP",      "N",       "number of steps",     "number of steps",   false, true,  true,  1,      1e9,        false, false, true,  "",         0,   0, LPFDM_OF(steps)},
    {"SHAKE",     "SCALE",   "SCALE (the record times this)", "SCALE", true, false, true, -kHuge, kHuge,      true,  true,  false, "",         1,   0, LPFDM_AT(shakes, scale)},
    {"SHAKE",     "START",   "START (model time of the record's time 0, s)", "START", true, false, true, 0, kHuge, false, true,  false, "",         0,   0, LPFDM_AT(shakes, start)},
    {"SHAKE",     "DAMPING", "DAMPING (local damping alpha from START on)", "SHAKE DAMPING", true, false, true, 0, 1, false, true, false, "",     -1,   0, LPFDM_AT(shakes, damping)},
    {"OUTPUT",    "EVERY",   "EVERY n",             "EVERY n",           true,  false, true,  1,      1e9,        false, false, true,  "",         0,   0, LPFDM_AT(outputs, every)},
    {"WATER",     "KW",      "the water's bulk modulus, Pa", "KW",       true,  false, true,  0,      kHuge,      true,  true,  false, "",       2.2e9, 0, LPFDM_OF(water.kw)},
    {"WATER",     "RHOW",    "the water's density, kg/m^3", "RHOW",      true,  false, true,  0,      kHuge,      true,  true,  false, "",       1000,  0, LPFDM_OF(water.rhow)},
    {"WATER",     "TABLE",   "phreatic level y, m", "TABLE",             true,  false, true,  -kHuge, kHuge,      true,  true,  false, "",       -kHuge, 0, LPFDM_OF(water.table)},
    {"RESERVOIR", "LEVEL",   "level y of the water's surface, m", "the reservoir's level", false, true, true, -kHuge, kHuge, true, true, false, "", 0, 0, LPFDM_OF(reservoir.level)},
    {"RESERVOIR", "TO",      "level y it is lowered to, m", "TO",        true,  false, true,  -kHuge, kHuge,      true,  true,  false, "",       -kHuge, 0, LPFDM_OF(reservoir.to)},
    {"RESERVOIR", "START",   "model time the change starts, s", "START", true,  false, true,  0,      kHuge,      false, true,  false, "",         0,   0, LPFDM_OF(reservoir.start)},
    {"RESERVOIR", "OVER",    "duration of the change, s", "OVER",        true,  false, true,  0,      kHuge,      false, true,  false, "",         0,   0, LPFDM_OF(reservoir.over)},
    {"GEOSTATIC", "K0",      "sigma'_xx / sigma'_yy at rest (default nu / (1 - nu))", "K0", true, false, true, 0, 10,    false, false, false, "",        -1,   0, LPFDM_OF(k0)},
    {"DRAIN",     "X0",      "x0",                  "x0",                false, true,  true,  -kHuge, kHuge,      true,  true,  false, "",         0,   0, LPFDM_AT(drains, box.x0)},
    {"DRAIN",     "Y0",      "y0",                  "y0",                false, true,  true,  -kHuge, kHuge,      true,  true,  false, "",         0,   0, LPFDM_AT(drains, box.y0)},
    {"DRAIN",     "X1",      "x1",                  "x1",                false, true,  true,  -kHuge, kHuge,      true,  true,  false, "",         0,   0, LPFDM_AT(drains, box.x1)},
    {"DRAIN",     "Y1",      "y1",                  "y1",                false, true,  true,  -kHuge, kHuge,      true,  true,  false, "",         0,   0, LPFDM_AT(drains, box.y1)},
    {"LOAD",      "X0",      "x0",                  "x0",                false, true,  true,  -kHuge, kHuge,      true,  true,  false, "",         0,   0, LPFDM_AT(loads, box.x0)},
    {"LOAD",      "Y0",      "y0",                  "y0",                false, true,  true,  -kHuge, kHuge,      true,  true,  false, "",         0,   0, LPFDM_AT(loads, box.y0)},
    {"LOAD",      "X1",      "x1",                  "x1",                false, true,  true,  -kHuge, kHuge,      true,  true,  false, "",         0,   0, LPFDM_AT(loads, box.x1)},
    {"LOAD",      "Y1",      "y1",                  "y1",                false, true,  true,  -kHuge, kHuge,      true,  true,  false, "",         0,   0, LPFDM_AT(loads, box.y1)},
    {"LOAD",      "TX",      "traction in x, Pa",   "TX",                true,  false, true,  -kHuge, kHuge,      true,  true,  false, "",         0,   0, LPFDM_AT(loads, tx)},
    {"LOAD",      "TY",      "traction in y, Pa",   "TY",                true,  false, true,  -kHuge, kHuge,      true,  true,  false, "",         0,   0, LPFDM_AT(loads, ty)},
    {"TRACK",     "X",       "x (m)",               "the tracked x",     false, true,  true,  -kHuge, kHuge,      true,  true,  false, "",         0,   0, LPFDM_AT(tracks, x)},
    {"TRACK",     "Y",       "y (m)",               "the tracked y",     false, true,  true,  -kHuge, kHuge,      true,  true,  false, "",         0,   0, LPFDM_AT(tracks, y)},
};
#undef LPFDM_AT
#undef LPFDM_OF

// The cards, in the order the deck reference lists them: the words around the numbers
// of kDeckKeys, and what the card does.
struct DeckCard {
    const char* name;
    const char* before;  // words before the positional fields
    const char* after;   // words after them (before the parameters)
    const char* meaning;
};
inline const DeckCard kDeckCards[] = {
    {"TITLE", "text", "", "a title for the output headers"},
    {"GRID", "", "", "the lattice: mx x my square cells of side L, origin at the lower-left corner"},
    {"MATERIAL", "", "ELASTIC|MOHR", "an elastic or Mohr-Coulomb material (SI units, angles in degrees)"},
    {"CLUSTER", "", "", "PPC x PPC points in every cell whose centre lies in the box [m]"},
    {"FIX", "X|Y|XY", "", "nodes in the box held in that direction"},
    {"WALL", "", "[SMOOTH|ROUGH]", "nodes in the box driven at (VX, VY) m/s; a line inside the material drives the material line it started on, others pass to the next line of nodes after each cell; no point crosses its faces; SMOOTH: a line driven across itself only"},
    {"SHAKE", "X|Y FILE=motion.txt", "[COMPLIANT] [BASELINE]", "ground acceleration history (time s, m/s^2): fixed nodes move with the ground, or COMPLIANT: it enters through an absorbing base"},
    {"ABSORB", "BOTTOM|TOP|LEFT|RIGHT ...", "", "viscous dashpots rho c_p (normal) and rho c_s (shear) on those edges of the lattice: outgoing waves leave"},
    {"OUTFLOW", "BOTTOM|TOP|LEFT|RIGHT ...", "", "material is meant to leave the lattice through those edges (an opening under it draws no warning)"},
    {"WATER", "", "[UNDRAINED]", "pore water in the materials with POROSITY: the models see effective stress, the lattice total stress; Darcy flow between cells (UNDRAINED: none)"},
    {"RESERVOIR", "", "", "free water outside the material, its surface at LEVEL, lowered to TO from START over OVER seconds: its hydrostatic pressure on the material's free surfaces below it, which it drains"},
    {"DRAIN", "", "", "cell edges whose two nodes lie in the box hold the hydrostatic pore pressure: water leaves or enters there"},
    {"LOAD", "", "", "a traction [Pa] on the nodes of a line, each its share of the line's length, carried by the material point nearest each node"},
    {"GEOSTATIC", "", "", "the points start at rest under gravity: sigma'_yy the weight above them in their column of cells (buoyant below the water table), sigma'_xx = sigma'_zz = K0 sigma'_yy"},
    {"GRAVITY", "", "", "gravity [m/s^2]"},
    {"DAMPING", "", "", "local non-viscous damping, eq. 13-14; WINDOW=t: about each node's mean motion over t s, so a steady flow is not held back"},
    {"HOURGLASS", "", "", "viscous control of the checkerboard mode eq. 5 cannot see (0: off)"},
    {"MOTION", "PAPER|CENTRE|BILINEAR", "", "how points move with their cell: eq. 7a/7b about node [1], about the centre, or bilinear"},
    {"MAPPING", "PAPER|SMOOTH", "", "a point in the cell holding its centre (the paper), or shared by the cells its square overlaps (no jump at cell edges)"},
    {"ADVECT", "EQ12|POINTS|FLIP", "", "how increments follow the material: eq. 12, carried by the points, or kept by them (FLIP)"},
    {"SHIFT", "", "", "every 10 steps, points that crowd (their squares' area over ABOVE times the area they lie in) move apart, down the crowding's gradient; after every step, a cell's points over twice its area move to neighbours with room (at most 8 a cell a step)"},
    {"SEED", "", "", "seed of the strength scatter"},
    {"REORDER", "", "", "sort the points' storage by cell every n steps (default 50; 0: never), for speed as points move"},
    {"STEP", "", "", "n steps of dt seconds"},
    {"OUTPUT", "POINTS|HISTORY|VTU|STATE file", "[BINARY] [NODES]", "a point table, a history, a VTK series (VTU) or a restart file (STATE), every n steps"},
    {"TRACK", "", "", "the history follows the point nearest (x, y) at step 0: columns tN_x tN_y tN_ux tN_uy"},
    {"END", "", "", "the end of the deck (optional)"},
};

// -------------------------------------- materials, points, the lattice's index boxes ---

// Elastic constants and strength of a material in the form the step uses.
struct MaterialConstants {
    Model model = Model::Elastic;
    double a1 = 0, a2 = 0, G = 0;   // K + 4G/3, K - 2G/3, G
    double inv_K = 0, inv_2G = 0;   // 1 / K, K = (a1 + 2 a2) / 3, and 1 / (2G): compliance_product's
    double rho = 0;
    // Mohr-Coulomb (means; per-point values replace c and n_phi when scattered)
    double c = 0, n_phi = 1, n_psi = 1, tension = -1, soften = 0;
    double sqrt_n_phi = 1;           // of the mean n_phi, taken once
    bool scatter = false;
    int user = -1;                   // index of a user model
};

// Strength of one Mohr-Coulomb point at this moment.
struct MohrStrength {
    double c = 0, n_phi = 1, n_psi = 1;
    double tension = -1;     // < 0: apex c / tan(phi)
    double sqrt_n_phi = 0;   // sqrt(n_phi) when known (per material); 0: taken here
};

// What a plastic correction did (principal plastic strains, tension positive).
struct MohrResult {
    enum Mode : std::uint8_t { Elastic = 0, Shear = 1, Tension = 2, Edge = 3 } mode = Elastic;  // Edge: 2-3 planes at once
    double d_gamma_p = 0;  // |d_eps1^p - d_eps3^p|: plastic shear strain increment
    double d_vol_p = 0;    // d_eps1^p + d_eps2^p + d_eps3^p
};

// Per-point state a constitutive model may read and change (eq. 6's s_1, s_2, ...).
struct PointState {
    double plastic_shear = 0;  // accumulated plastic shear strain
    bool yielded = false;      // has yielded at least once
};

// A user constitutive model with eq. 6's signature.
using UserModel = std::function<void(const StrainIncrement&, Stress&, PointState&)>;

// ------------------------------------------------------ lattice, points ---

// Points as a structure of arrays, sized once per scene. Every array in use has one
// entry per point; each_array is the one list of them (allocation, removal of points
// that left, memory estimates and counts go through it).
struct Points {
    std::vector<double> x, y, sxx, syy, sxy, szz, vol;
    std::vector<std::int32_t> cell, id;     // cell: the cell holding (x, y); a program that moves a point sets both
    std::vector<std::uint16_t> group;       // index into Simulation::groups(): material and mass
    // Only when some material is Mohr-Coulomb:
    std::vector<double> plastic_shear;
    std::vector<std::uint8_t> yielded;
    std::vector<double> plastic_work;       // work dissipated by the point's plastic returns [J/m]
    // Only when some material scatters: intact cohesion, N_phi and sqrt(N_phi) of each
    // point (the root taken once, not per step; a program that changes n_phi sets both).
    std::vector<double> c0, n_phi, sqrt_n_phi;
    // Scratch of the fast kernel's threaded point pass, not state: the points each thread
    // lists for adding after the pass (with threads), and for ADVECT POINTS a listed
    // point's own increment and the cell it left.
    std::vector<std::int32_t> listed;
    std::vector<double> carry_dx, carry_dy;
    std::vector<std::int32_t> carry_from;
    // ADVECT FLIP: the point's own increment in x and y over the last step [m] (its
    // velocity times dt), state.
    std::vector<double> flip_ux, flip_uy;
    // WATER: the pore pressure p [Pa, compression positive] of a saturated point (0 for a
    // dry one), and its volume when p last took its volume change (Simulation::water_pass).
    std::vector<double> pw, wvol;
    // LOAD: the force [N/m] a point carries for the LOAD cards (0 for most points), and
    // across which axis its line lies (1: a row of nodes, its normal y; 2: a column).
    std::vector<double> load_x, load_y;
    std::vector<std::uint8_t> load_axis;

    std::size_t size() const { return x.size(); }
    // Which scenes hold an array: every one, with a Mohr-Coulomb material, with scatter,
    // with more than one thread, with ADVECT POINTS and threads, with ADVECT FLIP.
    enum Use : std::uint8_t { kAlways, kPlastic, kScatter, kThreads, kCarry, kFlip, kWater, kLoad };
    // f(name, array, use, state) for every array above, in this order; state: part of a
    // point's state (not scratch).
    template <class F> void each_array(F&& f) { visit(*this, f); }
    template <class F> void each_array(F&& f) const { visit(*this, f); }

private:
    template <class P, class F> static void visit(P& p, F& f) {
        f("x", p.x, kAlways, true); f("y", p.y, kAlways, true);
        f("sxx", p.sxx, kAlways, true); f("syy", p.syy, kAlways, true); f("sxy", p.sxy, kAlways, true); f("szz", p.szz, kAlways, true);
        f("vol", p.vol, kAlways, true); f("cell", p.cell, kAlways, true); f("id", p.id, kAlways, true); f("group", p.group, kAlways, true);
        f("plastic_shear", p.plastic_shear, kPlastic, true); f("yielded", p.yielded, kPlastic, true);
        f("plastic_work", p.plastic_work, kPlastic, true);
        f("c0", p.c0, kScatter, true); f("n_phi", p.n_phi, kScatter, true); f("sqrt_n_phi", p.sqrt_n_phi, kScatter, true);
        f("listed", p.listed, kThreads, false);
        f("carry_dx", p.carry_dx, kCarry, false); f("carry_dy", p.carry_dy, kCarry, false); f("carry_from", p.carry_from, kCarry, false);
        f("flip_ux", p.flip_ux, kFlip, true); f("flip_uy", p.flip_uy, kFlip, true);
        f("pw", p.pw, kWater, true); f("wvol", p.wvol, kWater, true);
        f("load_x", p.load_x, kLoad, true); f("load_y", p.load_y, kLoad, true); f("load_axis", p.load_axis, kLoad, true);
    }
};

// Points of one material and one initial spacing share a mass and constants.
struct Group {
    int mat_index = 0;
    double mass = 0;  // kg per metre of thickness, a multiple of the mass quantum
    double vol0 = 0;  // initial volume m / rho: the most a point smears in eq. 8
    double half = 0;  // half the side of the square a point stands for, L / (2 PPC) (MAPPING SMOOTH)
};

struct WallState {
    std::vector<int> base_i, base_j;  // nodes of the box at the start
    int shift_i = 0, shift_j = 0;     // whole cells travelled
    double fx = 0, fy = 0;            // force the wall exerts on the material [N/m]
    double dx = 0, dy = 0;            // travel [m]
    double dx0 = 0, dy0 = 0;          // travel before the last increment: the next point pass moves the points
                                      // (and the wall's face) from there to (dx, dy)
    bool normal_x = false, normal_y = false;  // a smooth wall: drives only x (a column of nodes) or y (a row)
    Box face;                                 // the box of its nodes at the start [m] (hold_by_walls)
    // A line of nodes with material on one side only (or, farther than a cell on both
    // sides, on the side it is driven towards): the direction from the wall to it along the
    // normal (+1 or -1 in x for a column, in y for a row). Such a wall only pushes: a node
    // it would have to pull is left free. 0 (bonded): material on both sides within a cell
    // (the paper's cap), a box of nodes, a line with no material along it inside the
    // lattice, or with material far on both sides and not driven across itself
    // (Simulation::contact_side).
    int side_x = 0, side_y = 0;
    bool embedded = false;  // a row or column of nodes with material on both sides (drive_embedded)
};

struct Range {  // half-open index box
    int i0 = 0, i1 = 0, j0 = 0, j1 = 0;
    bool empty() const { return i0 >= i1 || j0 >= j1; }
    long size() const { return empty() ? 0 : long(i1 - i0) * (j1 - j0); }  // the cells or nodes it holds
    Range unite(const Range& o) const {
        if (empty()) return o;
        if (o.empty()) return *this;
        return {std::min(i0, o.i0), std::max(i1, o.i1), std::min(j0, o.j0), std::max(j1, o.j1)};
    }
    Range grow(int n, int imax, int jmax) const {
        if (empty()) return *this;
        return {std::max(0, i0 - n), std::min(imax, i1 + n), std::max(0, j0 - n), std::min(jmax, j1 + n)};
    }
};
namespace detail {

// A count that threads add to (Simulation's parked points), copied with its simulation.
struct Tally {
    std::atomic<long> n{0};
    Tally() = default;
    Tally(const Tally& o) : n(o.n.load()) {}
    Tally& operator=(const Tally& o) { n = o.n.load(); return *this; }
    void add() { n.fetch_add(1, std::memory_order_relaxed); }
    long take() { return n.exchange(0); }
};

// WATER, per group of points: Kw / n (0: dry), k / gamma_w, n, and V0.
struct GroupWater { double kwn = 0, mobility = 0, n = 0, vol0 = 0; };
// What water_pass's passes over the points read and write, by value: in the loops'
// registers (members or captures reached through memory are reloaded after every store).
struct WaterPoints {
    std::size_t n = 0;
    const std::int32_t* cell = nullptr;
    const std::uint16_t* group = nullptr;
    const GroupWater* gw = nullptr;
    const double *x = nullptr, *y = nullptr, *vol = nullptr;
    double *pw = nullptr, *wvol = nullptr;
    double rw = 0, gx = 0, gy = 0;
    bool flow = false, flip = false, smooth = false;
};

// MAPPING SMOOTH: a point's square across the cells (square_overlap along each axis): its
// first cell (a, b), the fractions of the square in that cell and the next along x and y,
// and the centres of those parts.
struct Overlap {
    int a = 0, b = 0;
    double wx[2] = {}, wy[2] = {}, cx[2] = {}, cy[2] = {};
};

#if LPFDM_WIDE
// Four doubles (and four lane masks) as GCC/Clang vectors: AVX2 registers inside a
// function built for AVX2; four cell or node numbers.
typedef double v4d __attribute__((vector_size(32)));
typedef long long v4m __attribute__((vector_size(32)));
typedef int v4i __attribute__((vector_size(16)));
typedef float v4f __attribute__((vector_size(16)));
// The strain increments of eq. 5a-5d of four cells (four points' cells) in the lanes.
struct StrainLanes { v4d xx, yy, xy, yx; };
#endif
#if LPFDM_WIDE
// The point arrays the consult in lanes reads and writes.
struct ConsultArrays {
    double *sxx, *syy, *sxy, *szz;
    const double* vol;
    const std::uint16_t* group;
    const double *c0, *n_phi, *sqrt_n_phi;  // each point's own strength (scatter), or null
    std::uint8_t* yielded;
    double *plastic_shear, *plastic_work;
    bool at_vol0;  // the plastic work on V0 (ADVECT FLIP), not on min(V, V0): Simulation::energy_volume
};
#endif
// The ground's motion under one SHAKE card, step by step (Simulation::ground_step, and the
// warning's ground_excursion): step n (from time n dt to (n + 1) dt) is integrated as eq.
// 13 integrates a node, v(n + 1/2) = v(n - 1/2) + dt a(n dt), with dt a(n dt) the record's
// exact integral over the step's time, from (n - 1/2) dt to (n + 1/2) dt: v(n + 1/2) is then
// the record's velocity at (n + 1/2) dt exactly (a record starting with a jump or sampled
// coarser than dt loses nothing), du = v dt.
struct GroundMotion {
    const Shake* spec = nullptr;  // the card (nullptr: this direction is not shaken)
    bool rigid() const { return spec && !spec->compliant; }  // it moves the fixed nodes (not COMPLIANT)
    double c0 = 0, c1 = 0;        // BASELINE: the trend c0 + c1 t taken off the acceleration
    long first = 0;               // start_step
    std::size_t at = 0;           // the record's sample at or before the time last asked
    double v = 0;                 // velocity at the last half step [m/s]
    double du = 0, du_before = 0; // increment in this step and in the one before [m]
    double d = 0;                 // displacement after this step [m]
    double v_now = 0;             // velocity at the start of this step (mean of the half steps)
    void rewind() { at = 0; v = du = du_before = d = v_now = 0; }
    void step(long n, double dt);
};
}  // namespace detail

// -------------------------------------------------------------- checks ---

// What the deck reader could not read: its cards with errors and the cards it missed.
// validate() and warnings() skip the checks whose answer depends on them, so that one
// pass reports every problem of a deck and no echo of one (a bad MATERIAL card would
// also make its clusters "undefined"; a bad STEP card, its dt "not > 0" again).
struct Unread {
    bool grid = false;       // GRID bad or missing: no lattice to place anything on
    bool step = false;       // STEP bad or missing: no dt, no number of steps
    bool materials = false;  // a MATERIAL card bad, or an unknown card near it or near no card (a misspelt MATERIAL?)
    bool clusters = false;   // a CLUSTER card bad, or none at all (the reader said so)
    bool motion = false;     // a MOTION or ADVECT card bad: which pair was meant is unknown
    bool mapping = false;    // a MAPPING card bad: ADVECT FLIP's need of MAPPING SMOOTH is not checked
    bool fixes = false;      // a FIX card bad: whether SHAKE moves fixed nodes is not checked
    void all() { grid = step = materials = clusters = motion = mapping = fixes = true; }  // nothing read
};

// Which code runs the cycle, chosen once, when a Simulation is made:
//   Reference  the plain cycle (Simulation::step_reference): every cell, point and node,
//              one value at a time, one thread. The definition of a step.
//   Fast       the same cycle over the occupied part of the lattice only, by threads
//              (OpenMP), and four values per AVX2 register where the processor has it.
//   Scalar     Fast without AVX2.
// All three give the same numbers, bit for bit (tests/test_reference.cpp).
enum class Kernel : std::uint8_t { Fast, Scalar, Reference };
inline const char* kernel_name(Kernel k) { return k == Kernel::Reference ? "reference" : k == Kernel::Scalar ? "scalar" : "fast"; }

// What a scene switches on, read once from it when a Simulation is made (modes_of): every
// part of the cycle asks this, never whether some array happens to be empty.
struct Modes {
    Mapping mapping = Mapping::Paper;  // eq. 8's mapping: the paper's, or MAPPING SMOOTH (GIMP's)
    Motion motion = Motion::Centre;    // eq. 7a/7b's rule, never Default (SMOOTH: BILINEAR, else CENTRE)
    Advect advect = Advect::Eq12;      // what the lattice carries: eq. 12, ADVECT POINTS or ADVECT FLIP
    bool hourglass = false;            // HOURGLASS kappa > 0: the checkerboard's viscous force
    bool dynamic = false;              // SHAKE or ABSORB: ground motion, dashpots
    bool shake = false;                // SHAKE: ground motion (a part of dynamic)
    bool user = false;                 // a material has a user's model (Simulation::set_user_model)
    bool plastic = false;              // a Mohr-Coulomb material (or a user model): plastic shear and work
    bool scatter = false;              // SCATTER: each point its own strength
    bool water = false;                // WATER: pore pressure on the saturated points (water_pass)
    bool loads = false;                // LOAD cards: forces carried by points (load_forces)
    Kernel kernel = Kernel::Fast;      // the kernel that runs it (every kernel runs every mode)
    // Why the fast kernel takes the points one at a time where it has AVX2 (its lattice
    // phases keep their lanes), and why its point pass runs on one thread ("": it does not).
    const char* points_why = "";
    const char* threads_why = "";
};

// --------------------------------------------------------------------- the functions ---
class Simulation;
// Checks of a scene and of its deck (the checks section).
LPFDM_DEF void sort_diagnostics(std::vector<Diagnostic>& d);
LPFDM_DEF Diagnostics one_error(const std::string& file, int line, int col, std::string message);
LPFDM_DEF double stable_dt(const Scene& s);
// The largest local damping alpha the scene uses: DAMPING's, or a SHAKE's DAMPING= from
// its START on (stable_dt, DAMPING WINDOW).
inline double largest_damping(const Scene& s) {
    double alpha = std::max(0.0, s.damping);
    for (const Shake& k : s.shakes) alpha = std::max(alpha, k.damping);
    return alpha;
}
LPFDM_DEF double estimate_bytes(const Scene& s, double points);
LPFDM_DEF double count_points(const Scene& s);
LPFDM_DEF void refine(Scene& s, int k);
LPFDM_DEF std::string apply_setting(Scene& s, const std::string& key_in, double v);
LPFDM_DEF std::string shortest(double x);
LPFDM_DEF std::string nearest_name(const std::string& written, const std::vector<std::string>& candidates);
LPFDM_DEF std::string did_you_mean(const std::string& written, const std::vector<std::string>& candidates);
LPFDM_DEF std::vector<std::string> card_names();
LPFDM_DEF std::string card_synopsis(const DeckCard& c);
LPFDM_DEF std::string deck_help();
LPFDM_DEF Modes modes_of(const Scene& s, Kernel asked);
LPFDM_DEF Diagnostics validate(const Scene& s, const Unread& unread = Unread());
LPFDM_DEF Diagnostics warnings(const Scene& s, const Unread& unread = Unread());
LPFDM_DEF std::string record_problem(const Shake& k);

// A scene is at rest when its unbalanced-force ratio (Simulation::unbalanced_ratio: the
// largest unbalanced nodal force over the mean gross one) is below this. The ratio takes
// the largest force, not the mean, so the bound is FLAC's classic 1e-3 rather than its
// 1e-5 for a mean: decks/column.deck falls below it at step 1900 of 6000 and ends at 1e-10,
// a slope still settling after an earthquake (decks/quake_slope.deck) ends at 0.01, a
// collapsing cliff (decks/cliff.deck) stays above 0.19.
inline constexpr double kAtRest = 1e-3;
// Factor of safety by strength reduction (lpfdm --fos; the section FACTOR OF SAFETY).
struct FosTrial {
    double F = 0;         // the trial's factor
    bool stands = false;  // came to rest within the trial's steps
    long steps = 0;       // steps run: to rest, or the whole budget
    double ratio = 0;     // the unbalanced-force ratio at the end
    double moved = 0;     // the largest point displacement at the end [m]
    bool trouble = false; // the run went wrong (Simulation::healthy): it counts as failing
};
struct FosOptions {
    double tol = 0.01;                           // F is bracketed to within this
    double smallest = 1.0 / 16, largest = 16;    // the range of trial factors
    long responses = 8;                          // a trial's budget in response times N_r
    Kernel kernel = Kernel::Fast;
};
struct FosResult {
    enum Outcome { Found, FailsAtSmallest, StandsAtLargest, NeverAtRest } outcome = Found;
    double F = 0, stands_at = 0, fails_at = 0;   // F = (stands_at + fails_at) / 2
    long response_steps = 0;                     // N_r (NeverAtRest: the steps tried)
    long budget = 0;                             // each trial's steps: FosOptions::responses N_r
    double ratio = 0;                            // NeverAtRest: the ratio it ended at
    std::vector<FosTrial> trials;                // in the order run
};
LPFDM_DEF Scene strength_reduced(const Scene& s, double F);
LPFDM_DEF long response_steps(const Scene& s, Kernel k, double* ratio = nullptr);
LPFDM_DEF FosTrial fos_trial(const Scene& s, double F, long budget, Kernel k);
LPFDM_DEF FosResult factor_of_safety(const Scene& s, const FosOptions& o = FosOptions(),
                                     const std::function<void(const FosTrial&)>& told = nullptr);
// Where the factor found for s is not verified, as warnings at the cards concerned (the
// program prints them with --fos): a free face drawn across the lattice in soil too weak
// for a riser of one cell to stand.
LPFDM_DEF Diagnostics fos_warnings(const Scene& s);

#ifndef LPFDM_NO_IO
// The deck reader, the writers and the state files.
// How a run was made: what the provenance lines of each output file record.
struct RunInfo {
    std::string deck;                   // the deck's path as given
    std::uint64_t deck_digest = 0;      // fnv1a64 of its text
    std::vector<std::string> settings;  // each --set, KEY=VALUE as given, in order
    long steps = 0, refine = 1;         // --steps (0: not given), --refine
    long long seed = -1;                // --seed (-1: not given)
    int threads = 1;
    std::string kernel = "fast";
};
LPFDM_DEF Diagnostics load_file(const std::string& path, std::string& text, const char* what = "deck");
LPFDM_DEF Diagnostics read_motion(const std::string& path, Shake& k);
LPFDM_DEF Diagnostics parse_deck_text(const std::string& text, const std::string& file, Scene& sc, Unread* unread = nullptr);
LPFDM_DEF Diagnostics read_deck_text(const std::string& text, const std::string& file, Scene& sc);
LPFDM_DEF Diagnostics read_deck(const std::string& path, Scene& sc);
LPFDM_DEF std::uint64_t fnv1a64(const std::string& text);
// A number as a deck writes one (a Fortran real: 12000, 1.5E-3, 2D7; no nan or inf): false
// when text is not one, or does not fit a double.
LPFDM_DEF bool read_number(const std::string& text, double& out);
LPFDM_DEF void write_provenance(std::FILE* f, const Simulation& sim, const RunInfo& r);
LPFDM_DEF std::string history_columns(const Simulation& sim);
LPFDM_DEF void write_points_header(std::FILE* f, const Simulation& sim, const std::string& deck, const RunInfo* run = nullptr);
LPFDM_DEF void write_points_frame(std::FILE* f, const Simulation& sim, bool first);
LPFDM_DEF void write_history_header(std::FILE* f, const Simulation& sim, const std::string& deck, const RunInfo* run = nullptr);
LPFDM_DEF void write_history_row(std::FILE* f, const Simulation& sim);
LPFDM_DEF void write_vtu(std::FILE* f, const Simulation& sim, const std::vector<double>& x0, const std::vector<double>& y0, bool binary);
LPFDM_DEF void write_vti(std::FILE* f, const Simulation& sim, bool binary);
LPFDM_DEF std::string vtu_frame_file(const std::string& name, long step, bool nodes = false);
LPFDM_DEF void write_pvd(std::FILE* f, const std::vector<std::pair<std::string, double>>& frames);
LPFDM_DEF std::uint64_t state_digest(const std::string& deck_text, const std::string& options);
LPFDM_DEF bool write_state(std::FILE* f, const Simulation& sim, std::uint64_t digest);
LPFDM_DEF Diagnostics read_state(const std::string& path, Simulation& sim, std::uint64_t digest);

inline constexpr const char* kPointColumns = "x y sxx syy sxy szz ep yielded mat id ux uy";
#endif

// -------------------------------------------------------------------- the simulation ---

// The unit that defines LPFDM_IMPLEMENTATION defines this; a program without it fails to
// link, naming it (the Simulation constructor calls it).
namespace detail { LPFDM_DEF int define_LPFDM_IMPLEMENTATION_in_one_unit(); }

class Simulation {
public:
    explicit Simulation(const Scene& scene, Kernel kernel = Kernel::Fast) : Simulation(scene, kernel, detail::define_LPFDM_IMPLEMENTATION_in_one_unit()) {}

    // One LPFDM cycle (paper section 2), one function per phase.
    void step();
    // The same step by the reference cycle, whatever the kernel (see Kernel).
    void step_reference();
    Kernel kernel() const { return kernel_; }
    const Modes& modes() const { return modes_; }  // what the scene switches on, the kernel that runs it and why
    // Whether every step runs the reference cycle (the reference kernel).
    bool reference_only() const { return kernel_ == Kernel::Reference; }

    // Wall-clock seconds spent in each phase of step() while profiling is on: the phases
    // of the kernel that runs.
    static constexpr int kPhases = 5;
    static const char* phase_name(int k);
    void set_profiling(bool on) { profiling_ = on; }                 // time each phase from now on
    // The AVX2 version of the point loop (with the paper's motion rule; MAPPING SMOOTH's
    // and ADVECT FLIP's passes) and of the regular lattice phases: used when built in
    // (LPFDM_WIDE) and the processor has AVX2;
    // set_wide(false) takes the one-at-a-time loops (the same numbers, bit for bit).
    static bool have_wide();
    void set_wide(bool on);
    // Threads the fast kernel uses: omp_get_max_threads() when the Simulation was made
    // (1 for the reference kernel, or without OpenMP).
    int threads() const { return team_; }
    bool wide() const { return wide_; }
    const double* phase_seconds() const { return phase_s_; }          // kPhases entries, in step order
    // While profiling, the Mohr-Coulomb consult of the fast AVX2 point loop alone (eq. 6's
    // elastic test and plastic return, four points a register; part of the points phase):
    // its seconds (summed over threads) and the point-updates it consulted. Zero for the
    // other loops, which consult point by point inside the motion.
    double return_seconds() const { return return_s_; }
    long return_updates() const { return returned_; }
    // Bytes the point arrays hold per point (capacity, all arrays).
    double bytes_per_point() const;

    // Read access for writers, tests and embedding programs.
    const Scene& scene() const { return sc_; }                        // the scene as run (after set_* calls)
    const Points& points() const { return p_; }                       // the points, structure of arrays
    Points& points() { return p_; }  // e.g. to set an initial stress field before the first step
    // The storage positions of the points in the order of their ids (the order they were
    // made in): the storage order itself unless REORDER sorted it. Writers list points so.
    const std::vector<std::int32_t>& by_id() const;
    // Each point's position when the Simulation was made (step 0), by id [m]: the point
    // tables' displacement ux uy is x - initial_x()[id].
    const std::vector<double>& initial_x() const { return x0_; }
    const std::vector<double>& initial_y() const { return y0_; }
    // TRACK: the id of the point each card follows (the nearest to its (x, y) at step 0;
    // the lowest id of those as near), and the storage position of point id now (-1: it left).
    const std::vector<std::int32_t>& tracked() const { return tracked_; }
    long slot_of(std::int32_t id) const;
    const std::vector<Group>& groups() const { return groups_; }      // material and mass of each point group
    const std::vector<WallState>& walls() const { return walls_; }    // force and travel of each wall, deck order
    const std::vector<std::int32_t>& driven_nodes() const { return driven_nodes_; }  // the nodes the walls drove in the last step
    long step_count() const { return step_; }                         // steps taken
    // Moves clamped since step 0: a point that its cell's fixed edge or a wall's face
    // stopped (stop_at_edges), put back on its side of it. A boundary should hold by
    // constraining the lattice; each use of this last guard is counted.
    long parked() const { return parked_; }
    // Moves a fixed edge's nodes held since the simulation was made (a restart counts from
    // its step): a point that its cell's affine motion (eq. 7a/7b, MOTION CENTRE) would
    // have carried across a cell edge fixed across it moved across the edge with the
    // lattice's bilinear field instead, which those nodes hold (stop_at_edges).
    long held() const { return held_; }
    // The most volume one cell's points hold over the cell's area: the largest of eq. 8's
    // sums of the points' V (with MAPPING SMOOTH, of their squares' parts in the cell),
    // as mapped in the last step, over L^2. Points packing into a cell without being
    // compressed (a cell that swallows them) drive it up; material made at one volume a
    // cell and moved as a continuum keeps it near 1.
    double packing() const;
    // SHIFT: the point moves shift_points made since step 0.
    long shifted() const { return shifted_; }
    // WATER: the largest excess pore pressure over the points, p - rho_w |g_y| (TABLE - y)
    // at the point's place now [Pa] (0 without water), and the water that left through the
    // drains since step 0 [m^3/m] (entered: negative).
    double excess_pressure() const;
    double drained() const { return drained_; }
    bool water() const { return modes_.water; }
    bool loaded() const { return modes_.loads; }
    // The threaded point pass (advance_parted): steps it took, points it listed for the
    // serial add after it (landed in another thread's part of the cells), and steps it had to
    // map again (a thread's points landed in a later thread's part).
    struct PartedPass { long steps = 0, listed = 0, clashes = 0; };
    const PartedPass& parted_pass() const { return parted_; }
    // The lattice phases' loops by threads: how often their blocks of rows were cut anew
    // (the threads' times differed by more than 3 %; by_rows).
    long row_block_moves() const { return row_moves_; }
    double time() const { return step_ * sc_.dt_s; }                 // model time [s]
    double kinetic_energy() const { return ke_; }                     // nodal, at the last half step [J/m]
    double mass_inside() const { return mass_in_; }                   // [kg/m]
    double mass_outflow() const { return mass_out_; }                 // of the points that left [kg/m]
    double mass_initial() const { return mass0_; }                    // inside + outflow, exactly
    double unbalanced_ratio() const;                                  // max unbalanced / mean gross nodal force (after step() or integrate())
    // The energy account since the first step [J/m], every term summed in a fixed order
    // (the same numbers with every kernel and thread count):
    //   kinetic   of the nodes, (1/2) m du(t - dt/2) . du(t + dt/2) / dt^2: the leapfrog's
    //             own kinetic energy, which with the strain energy at t is conserved
    //             exactly by an undamped linear step (ke, the history's column, is
    //             (1/2) m (du(t + dt/2) / dt)^2, half a step later);
    //   strain    elastic energy of the points, V (1/2) sigma : C^-1 : sigma, V = min(V, m / rho)
    //             as in eq. 8 (compliance_product), less its value before the first step;
    //   gravity   potential energy of the points, -m g . x, less its value at the start;
    //   w_walls, w_fixes   work the walls and the fixed nodes did on the material;
    //   w_gravity work gravity did on the nodes (the points' potential energy moved by
    //             eq. 7a/7b instead: gravity + w_gravity is what the mapping gains or loses);
    //   d_damping dissipated by local damping (eq. 13, 14);
    //   d_plastic dissipated by the plastic returns (Points::plastic_work);
    //   error     (work in - kinetic - strain - gravity - dissipated) / max(|work in|, kinetic +
    //             |strain| + |gravity|, the largest kinetic energy so far, |dissipated|, 1e-10 of
    //             the strain and potential energies at the start), work in = w_walls + w_fixes +
    //             w_ground + w_loads + w_shift, dissipated = d_damping + d_plastic + d_absorb + d_water +
    //             d_slip: energy the discrete cycle created (< 0) or lost (> 0), as a fraction of
    //             the energy in play.
    // Nodal works are trapezoidal in time (the force at t and t + dt on the increment between).
    // Points that left the lattice keep the strain and potential energy they left with;
    // the kinetic energy of their nodes is lost and shows in the error. A user model's
    // dissipation is not known: its points count as elastic.
    //   w_ground  work of the ground motion (SHAKE: the shaken fixed nodes, or a compliant
    //             base's input traction); d_absorb  energy the dashpots of ABSORB took out;
    //   d_slip    (ADVECT FLIP) the supports' force on the slip between a support that changes
    //             speed (SHAKE's ground, a wall given a new velocity) and the material beside
    //             it (flip_slip); 0 in the other cycles, whose held nodes move with the material.
    //   w_shift   (SHIFT) the potential energy the points' moves apart gave them (shift_points),
    //             counted as work in.
    struct Energy {
        double kinetic = 0, strain = 0, gravity = 0, w_walls = 0, w_fixes = 0, w_gravity = 0, d_damping = 0, d_plastic = 0, error = 0;
        double w_ground = 0, d_absorb = 0;
        double w_loads = 0, d_water = 0;  // LOAD's work; WATER: the stored water energy the flow and drains took out
        double d_slip = 0;                // ADVECT FLIP: the slip between a support changing speed and the material (flip_slip)
        double w_shift = 0;               // SHIFT: the potential energy the moves apart gave the points (shift_points)
    };
    Energy energy() const;
    double reaction_x() const { return rx_; }                         // sum of fixed-node reactions [N/m]
    // The reaction of FIX card f (deck order; a node held by several cards counts for the first).
    double fix_reaction_x(std::size_t f) const { return fix_rx_[f]; }
    double fix_reaction_y(std::size_t f) const { return fix_ry_[f]; }
    double reaction_y() const { return ry_; }
    int mx() const { return mx_; }                                    // cells in x
    int my() const { return my_; }                                    // cells in y
    double cell_size() const { return L_; }                           // L [m]
    int node(int i, int j) const { return j * (mx_ + 1) + i; }        // index of node (i, j)
    int cell(int i, int j) const { return j * mx_ + i; }              // index of cell (i, j)
    double point_mass(std::size_t k) const { return groups_[p_.group[k]].mass; }
    int material_id(std::size_t k) const { return sc_.materials[groups_[p_.group[k]].mat_index].id; }

    // Nodal and cell fields (whole lattice, row-major).
    std::vector<double>& du_x() { return dux_; }                      // nodal increments du_x [m]
    std::vector<double>& du_y() { return duy_; }
    const std::vector<double>& du_x() const { return dux_; }
    const std::vector<double>& du_y() const { return duy_; }
    const std::vector<double>& force_x() const { return fx_; }        // net nodal force, gravity included [N/m]
    const std::vector<double>& force_y() const { return fy_; }
    const std::vector<double>& node_mass() const { return nmass_; }   // lumped mass, eq. 10 [kg/m]
    const std::vector<double>& cell_mass() const { return cmass_; }   // eq. 7 [kg/m]
    const std::vector<double>& cell_volume() const { return cvol_; }  // eq. 8: the sum of the points' V [m^2/m]

    // Changes a wall's velocity from the next step on (staged loading; 0 holds it).
    void set_wall_velocity(int wall_id, double vx, double vy);

    // Replace the constitutive model of a material by a callable of eq. 6's signature.
    void set_user_model(int mat_id, UserModel f);

    // The cell a point at (x, y) belongs to (eq. 7: the half-open lattice box, the cell
    // floor(x / L), floor(y / L)); -1 outside the lattice or not finite. The reference cycle
    // bins by it; the fast kernel's landing makes the same test in its registers.
    int cell_holding(double x, double y) const;
    // Strain increments of cell (i, j) from the nodal increments, eq. 5a-5d.
    StrainIncrement strain_of_cell(int i, int j) const;

    // The point a non-finite value was first seen at, or -1.
    long first_nonfinite_point() const;
    bool healthy() const { return std::isfinite(ke_) && max_du_ <= 0.5 * L_; }  // finite, no node beyond half a cell a step
    // The node with the largest (or a non-finite) increment, and a point in a cell beside
    // it (-1 if none): where a run that stopped went wrong.
    void worst_node(int& i, int& j, long& point) const;
    double max_du() const { return max_du_; }                         // largest nodal increment of the last step [m]
    // SHAKE: the ground's increment in the last step and its displacement after it [m]
    // (axis 0: x, 1: y; zero where nothing shakes).
    double ground_increment(int axis) const { return ground_[axis].du; }
    double ground_displacement(int axis) const { return ground_[axis].d; }
    bool dynamic() const { return modes_.dynamic; }                          // the scene shakes or absorbs (SHAKE, ABSORB)

    // Restart files (write_state, read_state). What a step reads from the steps before it,
    // besides the scene and the points: f(name, member) for the step count and the running
    // sums, the nodal increments (eq. 12 compensates them, eq. 13 advances them), the node
    // masses (eq. 12 compares the next step's with them), the cell masses (eq. 5 skips the
    // empty cells), each wall's travel (now and before the last increment), line and
    // velocity, and the energy account's running sums. Every other lattice array
    // is made by a step before that step reads it (resumed() clears them). The random
    // numbers are drawn when the points are made (their c0 and n_phi keep them): no
    // generator state lives on. None of it depends on the kernel or the threads.
    // (each_state needs the implementation: the state files' reader and writer use it)
    template <class F> void each_state(F&& f) { visit_state(*this, f); }
    template <class F> void each_state(F&& f) const { visit_state(*this, f); }
    // After each_state and the points' arrays were set from a file: the lattice arrays a
    // step makes before it reads them cleared (outside the fast kernel's boxes they must be
    // zero), the fast kernel's record of the active lattice made anew from the points
    // (every node taken as live, which only costs the first step a visit of the whole
    // lattice), the threads' point chunks and scratch sized to the points. Either kernel
    // may continue either's state.
    void resumed();

    // The phases of step(), in order; public so that tests and lessons can step
    // through one cycle. Normal use calls step().
    void cell_strains();
    void update_points() { point_pass(); }  // eq. 6, 7a/7b, and (in the same pass) eq. 7, 8
    void map_to_lattice() { map_points(); }
    void nodal_forces();
    void compensate();
    void integrate();

private:
    Simulation(const Scene& scene, Kernel kernel, int);  // (the public constructor's, with the implementation's mark)
    // MAPPING SMOOTH: the strain increments of a point whose square is o, the mean over the
    // square of the gradient of the lattice's increment field, its trace taken at the
    // centroids of the cells' material (centroid_trace_, made once a step by
    // centroid_traces for every cell holding material); with motion, (dx, dy) the mean
    // increment over the square (MOTION BILINEAR).
    LPFDM_INLINE StrainIncrement smooth_strain(const detail::Overlap& o, bool motion, double& dx, double& dy) const;
    // MAPPING SMOOTH: f(i, j, x, y, w) for each part of the square o (overlap_of: the square
    // of half-width l about (x0, y0), square_overlap along each axis): the cell (i, j) it
    // lies in, the part's centre (x, y) and its share w > 0 of the square, in row order.
    template <class F> LPFDM_INLINE void each_part(const detail::Overlap& o, F&& f) const;
    detail::Overlap overlap_of(double x0, double y0, double l) const;
    // MAPPING SMOOTH: each point's square as the map left it (smooth_map), read by the rest
    // of the step (FLIP's transfer; the points do not move again in it) and by the next
    // step's first pass (smooth_move), where the points still are. overlaps_known_: false
    // once the points' storage changed order (reorder_points): the next pass finds them
    // again (known_overlaps).
    std::vector<detail::Overlap> overlap_;
    bool overlaps_known_ = false;
    void known_overlaps();
    void centroid_traces(const Range& cells);
    void cell_centroid(std::size_t c, double& u, double& v) const;  // from the centre, in cells
    // MAPPING SMOOTH: after eq. 13-14 and the supports, each node of `nodes` that only the
    // edges of points' squares reach (no point in any of its cells) moved again, in each
    // direction no support sets, with the part of its eq. 10 mass that its material's
    // position does not give it following the material beside it (its section).
    void follow_material(const Range& nodes);
    std::vector<std::uint8_t> holds_point_;  // MAPPING SMOOTH: per cell, 1 when a point lies in it (set by smooth_map for follow_material)
    // MAPPING SMOOTH: cell c's moments (shx, shy) made ready for the nodal forces, after
    // eq. 8 scaled its sums V sigma: the transpose of smooth_strain's variation across the
    // cell, times 2L (the forces divide by L, the sums were divided by 2L).
    void smooth_moment(std::size_t c);
    template <class S, class F> static void visit_state(S& s, F& f);
    void setup();
    void create_points();
    void remove_departed();
    bool reorder_due() const { return sc_.reorder > 0 && step_ % sc_.reorder == 0; }
    void reorder_points();
    std::size_t made_ = 0;                           // points made at set-up (ids 0 .. made_-1)
    std::vector<double> x0_, y0_;                    // their positions then, by id (initial_x)
    std::vector<std::int32_t> tracked_;              // TRACK: the points the cards follow (tracked())
    std::vector<std::int32_t> sorted_, cell_count_;  // reorder_points: the new order, points per cell
    std::vector<unsigned char> sort_buf_;            // reorder_points: one array in the new order
    mutable std::vector<std::int32_t> by_id_, slot_of_id_;  // by_id(): storage positions in id order
    void clear_cells();
    void clear_row(int j, int lo, int hi);
    void advance_points();
    bool advance_parted();
    // Where a range of points landed in the point pass: the cells and columns, their mass,
    // how many left the lattice (occupied_, mass_in_ and the outflow come from it).
    struct Landing {
        int cmin = std::numeric_limits<int>::max(), cmax = -1, imin = std::numeric_limits<int>::max(), imax = -1;
        double mass = 0;
        long departed = 0;
        // Another range's cells, mass and departures, added to these.
        void merge(const Landing& a) {
            mass += a.mass; departed += a.departed;
            cmin = std::min(cmin, a.cmin); cmax = std::max(cmax, a.cmax);
            imin = std::min(imin, a.imin); imax = std::max(imax, a.imax);
        }
    };
    void smooth_map(Landing& t);
    // Which of a cell's sums smear_point adds to: all of them; ADVECT FLIP's first mapping,
    // whose stress sums no one reads (flip_second_half maps the points again): the mass,
    // volume, centroids and the cells touched; its second: all but the mass (the first's,
    // the same terms) and the cells touched.
    enum class Smear { All, Mass, Stress };
    template <Smear S> void smear_point(const detail::Overlap& o, double m, double v, double sxx, double syy, double sxy, int j0, int j1, Landing& t);
    template <Smear S> void smear_points(Landing& t);
    std::vector<long> row_points_;  // by_rows' share of rows between threads
    // With AVX2, smear_points' nine sums of a cell side by side, twelve doubles a cell from a
    // 32-byte boundary (detail::aligned32), zero between the passes (smear_lanes).
    std::vector<double> cell_rec_;
#if LPFDM_WIDE
    template <Smear S> __attribute__((target("avx2"))) void smear_lanes(int j0, int j1, Landing& t);
#endif
    template <class F> void by_rows(int n, const F& f) { by_rows(n, row_points_, f); }
    template <class F> void by_rows(int n, const std::vector<long>& counts, const F& f);
    // A thread's share of the threaded point pass (advance_parted): the cells own_lo ..
    // own_hi-1 take its chunk's sums directly; a point landing in any other cell is listed
    // in p_.listed[list_at ..] (listed of them). The defaults: every cell (one thread).
    struct Part {
        int own_lo = 0, own_hi = std::numeric_limits<int>::max();
        long list_at = 0, listed = 0;
        double seconds = 0;  // the time the chunk took (advance_parted balances the chunks)
        double return_seconds = 0;  // profiling: in the Mohr-Coulomb consults of the AVX2 loop (consult_block)
        long returned = 0;          // ... and the point-updates they consulted
    };
    // The cells a range's points landed in, as a box of whole rows (occupied_).
    Range landed(const Landing& t) const { return t.cmax < 0 ? Range{} : Range{t.imin, t.imax + 1, t.cmin / mx_, t.cmax / mx_ + 1}; }
    // Points per block of the AVX2 point loop with a Mohr-Coulomb material (run_points).
    static constexpr long kConsultBlock = 256;
    void advance_range(long k0, long k1, Part& part, Landing& t);
    void choose_point_loop();
    void (Simulation::*run_)(long, long, Part&, Landing&) = nullptr;  // the point loop (choose_point_loop)
    template <Motion M> void advance_run(long k0, long k1, Part& part, Landing& t);
    // The point loop and its parts (the fast kernel's section): Blocks (with Wide, where some
    // group is Mohr-Coulomb): the points in blocks, each consulted four at a time between its
    // trial and its motion; otherwise run by run.
    struct Loop;
    enum : int { kWhole, kTrial, kMotion };  // the stages of runs
    template <Motion M, bool Wide, bool Blocks = false> LPFDM_INLINE void run_points(long k0, long k1, Part& part, Landing& t);
    template <Motion M, bool Wide, int S> LPFDM_INLINE void runs(Loop& lp, long k, long stop);
    template <bool Wide> LPFDM_INLINE long run_end(const Loop& lp, long k, long stop, int c) const;
    template <bool Wide> LPFDM_INLINE void run_trial(Loop& lp, long k, long kend, int c, bool& one_group);
    template <Motion M, bool Wide> LPFDM_INLINE void run_motion(Loop& lp, long k, long kend, int c, int ci, int cj, bool one_group);
    // eq. 7a/7b's nodes: the increments (ux, uy) of the four nodes of the cell whose node [1]
    // is n1, from the nodal increments (u, v) of a lattice of `row` nodes a row.
    LPFDM_INLINE void gather_nodes(int n1, double (&ux)[4], double (&uy)[4]) const;
    // MOTION CENTRE's mean increment (umx, umy) of those four nodes.
    LPFDM_INLINE void gather_mean(int n1, double& umx, double& umy) const;
#if LPFDM_WIDE
    // ... of four cells, node [1] of each in the lanes of n1.
    LPFDM_INLINE void gather_mean(const detail::v4i& n1, detail::v4d& umx, detail::v4d& umy) const;
    LPFDM_INLINE long usual_runs(Loop& lp, long k, long stop);
    LPFDM_INLINE void mohr_blocks(Loop& lp, long k0, long k1);
    LPFDM_INLINE void consult_timed(Loop& lp, long b0, long b1);
    LPFDM_INLINE void move_block(Loop& lp, long b0, long b1);
    LPFDM_INLINE void land_block(Loop& lp, long b0, long b1);
    LPFDM_INLINE static bool one_group_of_four(const std::uint16_t* pgroup, bool single, long q, int& g);
    LPFDM_INLINE detail::StrainLanes strain_lanes(const detail::v4i& c, bool one, detail::v4d& rc, detail::v4d& rs) const;
#endif
#if LPFDM_WIDE
    __attribute__((target("avx2"))) void advance_run_wide(long k0, long k1, Part& part, Landing& t);
    __attribute__((target("avx2"))) void advance_blocks_wide(long k0, long k1, Part& part, Landing& t);
    // The point loop's arrays of the stress, volume and group (run_points' own pointers).
    struct PointArrays { double *sxx, *syy, *sxy, *szz; const double* vol; const std::uint16_t* group; };
    // The Mohr-Coulomb consult in lanes, four points per AVX2 register (detail::lanes::consult);
    // the arrays it reads and writes, and
    // its one-point test and return of point r with elastic trial s (the stress stored).
    detail::ConsultArrays consult_arrays(const PointArrays& a);
    template <bool Own> void consult_one(const MaterialConstants& mc, long r, Stress s, const PointArrays& a);
    template <bool Own> __attribute__((target("avx2"))) void consult_lanes(const MaterialConstants& mc, long q, long qend, const PointArrays& a);
    // The Mohr-Coulomb points of b0 .. b1-1, holding their elastic trials, by spans of one
    // material (consult_lanes); the number consulted. Of the arrays a, or of the points.
    long consult_points(const PointArrays& a, long b0, long b1);
    long consult_points(long b0, long b1);
#endif
    // Row j of a lattice phase: f(j, std::false_type), or f(j, std::true_type) built for
    // AVX2 (f inlined into row_wide) when the AVX2 version is on, so that f may work
    // through the row four nodes or cells at a time in the lanes of a vector.
    template <class F> void each_row(const F& f, int j) const;
#if LPFDM_WIDE
    template <class F> __attribute__((target("avx2"))) static void row_wide(const F& f, int j) { f(j, std::true_type{}); }
#endif
    // The lattice phases' loops over rows (by_rows), each with its own blocks of rows by thread.
    enum RowLoop { kClearRows, kStrainRows, kSmearRows, kForceRows, kFillRows, kShiftRows, kCarryRows, kAdvanceRows, kEnergyRows, kWaterRows, kRowLoops };
    // Thread u's block of a loop's rows is rows[u] .. rows[u+1]-1, with edges at[u] as
    // fractions of the loop's range (which changes from step to step) for team threads;
    // seconds[u]: the time it took.
    struct RowBlocks {
        std::vector<double> at, seconds;
        std::vector<int> rows;
        int team = 0;
    };
    std::array<RowBlocks, kRowLoops> row_blocks_;
    long row_moves_ = 0;
    template <class F> void by_rows(RowLoop loop, int j0, int j1, long work, const F& f);
    void map_point(std::size_t k);
    // The points the team's chunks listed (p_.listed[list_at ..] of each Part), in chunk
    // order: eq. 7, 8.
    void add_listed(int team);
    // Node mass before and after this step's mapping: the node gained mass, and eq. 12 gives
    // it its neighbours' mean increment (compensate; nodal_forces marks its row).
    static bool gained_mass(double before, double now) { return !(before > 0 || now == 0); }
    // The sums of eq. 7 and 8 of one cell: mass, volume and V sigma. A run of points that
    // stay in one cell adds to a local copy (kept in registers) and stores it once.
    struct CellSums {
        double m, v, xx, yy, xy;
        // One point of mass pm, volume pv and stress (sxx, syy, sxy).
        void add(double pm, double pv, double sxx, double syy, double sxy) {
            m += pm;          // eq. 7
            v += pv;
            xx += pv * sxx;   // eq. 8
            yy += pv * syy;
            xy += pv * sxy;
        }
#if LPFDM_WIDE
        // The same for four points of one group, mass pm each, in the lanes of vol and
        // (sxx, syy, sxy), in point order (detail::add_four); mass: a running total that
        // takes the four masses too.
        LPFDM_INLINE void add_four(double pm, double vol0, const detail::v4d& vol, const detail::v4d& sxx, const detail::v4d& syy, const detail::v4d& sxy, double& mass);
#endif
    };
    CellSums cell_sums(std::size_t c) const { return {cmass_[c], cvol_[c], svxx_[c], svyy_[c], svxy_[c]}; }
    void store_sums(std::size_t c, const CellSums& a) { cmass_[c] = a.m; cvol_[c] = a.v; svxx_[c] = a.xx; svyy_[c] = a.yy; svxy_[c] = a.xy; }
    // eq. 7 and 8 for one point into cell c.
    void add_to_cell(std::size_t c, double m, double v, double sxx, double syy, double sxy);
    void map_points();
    // eq. 6's Mohr-Coulomb part: the return of point k's elastic trial s with its strength
    // (Own: its own c and N_phi), and its plastic shear if it yielded. vol: the point's volume
    // V now (the caller's: a fast loop holds V through a restrict pointer, which no other
    // access may read meanwhile).
    template <bool Own> LPFDM_INLINE void mohr_consult(const MaterialConstants& mc, std::size_t k, double vol, Stress& s);
    // Point q was returned from the trial stress to s with plastic shear increment
    // d_gamma_p: its plastic shear, its yielded flag and the work its return dissipated,
    // V s : C^-1 (trial - s), V = energy_volume: min(V, V0) as in eq. 8 (this step's volume:
    // every kernel changes V before the consult). The AVX2 point loop (detail::lanes::consult's
    // record) does the same four points at a time (never with ADVECT FLIP, which the reference cycle runs):
    // a change here is a change there.
    void record_yield(const MaterialConstants& mc, std::size_t q, double vol, double d_gamma_p, const Stress& trial, const Stress& s);
    void user_consult(const MaterialConstants& mc, std::size_t q, const StrainIncrement& e, Stress& s);
    void carried_increments(const Range& nodes);
    // ADVECT POINTS: the increment field a point of mass m brings to cell c = (i, j), where
    // it now lies at (x, y): d + E (x' - x), with E the eq. 5 strain of the cell it left.
    void carry_to(int c, int i, int j, double m, double x, double y, double dx, double dy, const StrainIncrement& e);
    // The smallest coordinate in cell k along an axis, and the largest in cell k - 1.
    double edge_above(int k) const;
    double edge_below(int k) const;
    bool serial() const;
    void step_profiled();
    // The fast kernel's point phase: eq. 6, 7a/7b and eq. 7, 8 in one pass, by threads
    // (advance_parted) or by one.
    void point_pass();
    // The reference cycle's phases, in step order.
    void reference_cell_strains();
    void reference_points();
    void reference_points_smooth();
    void move_with_cell(int ci, int cj, const StrainIncrement& e, double x0, double y0, double& x, double& y, double& dx, double& dy) const;
    void stop_at_edges(int c, double x0, double y0, double& x, double& y) const;
    LPFDM_INLINE void stop_at_edges(int ci, int cj, std::uint8_t fe, double x0, double y0, double& x, double& y) const;
    template <bool Trial> void smooth_move(std::size_t k);
    template <bool Move, class F> void each_point_consulted(const F& f);
    template <class F> void each_block(const F& f);
#if LPFDM_WIDE
    template <bool Move> __attribute__((target("avx2"))) void smooth_lanes(long b0, long b1);
    template <class F> __attribute__((target("avx2"))) void squares_lanes(long b0, long b1, const F& one);
#endif
    void smooth_point_pass();
    void reference_nodal_forces();
    void reference_compensate();
    void reference_integrate();
    // ADVECT FLIP (flip_transfer): the transfer, the stress's second half, eq. 13-14, each
    // on a box of nodes (cells) that holds every node (cell) with mass or an increment.
    void flip_transfer(const Range& nodes);
    void flip_second_half(const Range& nodes, const Range& cells);
    template <bool Trial> void flip_second_strain(std::size_t k);
    void flip_changes(const Range& nodes);
    void flip_point_change(std::size_t k, double& gx, double& gy) const;
    double flip_point_return(std::size_t k, double gx, double gy);
    void flip_return(const Range& nodes);
    Range flip_integrate(const Range& nodes, const Range& now);
    Range flip_nodes() const;
    template <class F> void each_point(const F& f);
    void zero_rows(const Range& r, int stride, std::initializer_list<std::vector<double>*> arrays);
    void nodal_kinetic(const Range& nodes);
    void smooth_node_force(int c, bool right, bool left, bool above, bool below, double& fx, double& fy) const;
    void hourglass_node_force(int c, bool right, bool left, bool above, bool below, double khg, double& fx, double& fy) const;
    template <class F> LPFDM_INLINE void flip_weights(std::size_t k, const F& f, int j0 = 0, int j1 = std::numeric_limits<int>::max()) const;
    template <bool Trial> void smooth_stress(std::size_t k, const StrainIncrement& e);
    // ADVECT FLIP's scratch: the nodes' masses by the points' weights, eq. 13's change of
    // each node and the points' change brought back (flip_sx_, flip_sy_ hold the walls'
    // and the fixed nodes' last increments in flip_transfer before that); the points'
    // kinetic energy (leapfrog).
    std::vector<double> flip_mass_, flip_ax_, flip_ay_, flip_sx_, flip_sy_;
    std::vector<double> flip_gx_, flip_gy_;  // each point's change in a step (flip_return), scratch
    // With AVX2, flip_transfer's and flip_return's nodal sums side by side, four doubles a
    // node (flip_sums_lanes), from a 32-byte boundary (detail::aligned32).
    std::vector<double> flip_rec_;
    void flip_sums(const Range& nodes, const double* vx, const double* vy, double* to0, double* to1, double* to2);
#if LPFDM_WIDE
    __attribute__((target("avx2"))) void flip_sums_lanes(int j0, int j1, double* rec, const double* vx, const double* vy);
#endif
    // A node direction a support held at the transfer, and the points' increment there (flip_slip).
    struct HeldStart { std::int32_t node; std::uint8_t dirs; double bx, by; };
    std::vector<HeldStart> flip_held_;
    void flip_slip();
    // SHIFT (shift_points): the fill of each cell of the lattice of spacing L/2 (the
    // sub-cells), its excess at each of that lattice's nodes; zero outside a step's box.
    std::vector<double> shift_fill_, shift_excess_;
    long shifted_ = 0;
    static constexpr long kShiftEvery = 10;  // steps between the passes
    static constexpr double kShiftLimit = 2;  // shift_relief: no cell's points over twice its area
    static constexpr int kShiftRounds = 8;    // shift_relief: at most so many moves out of one cell a step
    // A cell's whole points' volumes (shift_relief), the move it would make first (the point
    // nearest an edge whose neighbour has room, that edge 0-3) and its distance.
    struct ShiftCell {
        double sum = 0, best = std::numeric_limits<double>::infinity();
        long stamp = -1;  // the guard's call that wrote it (shift_stamp_): older entries read as empty
        std::int32_t point = -1;
        std::int8_t edge = -1;
        bool listed = false;  // in shift_full_
    };
    std::vector<ShiftCell> shift_cells_;
    std::vector<int> shift_full_;
    long shift_stamp_ = 0;
    void shift_points();
    bool shift_pass();
    bool shift_relief(double limit);
    bool shift_moved(double work, long moved, const Range& box);
    bool shift_may_move(std::size_t k) const;
    bool shift_may_cross(int c, int cn) const;
    double flip_kinetic_ = 0;
    // The node masses eq. 13 moves with: eq. 10's, or with ADVECT FLIP the transfer's M_n
    // (flip_changes). The fixed directions and the walls read the same masses, and the same
    // force F (with FLIP reference_integrate adds gravity's share of M_n - m_n to it);
    // SHAKE's shaken nodes and ABSORB's dashpots read them too.
    const std::vector<double>& inertia() const { return modes_.advect == Advect::Flip ? flip_mass_ : nmass_; }
    // eq. 6 for point k in a cell of strain increment e and rotation (rc, rs).
    void consult_model(std::size_t k, const MaterialConstants& mc, const StrainIncrement& e, double rc, double rs, Stress& s);
    // The strength of Mohr-Coulomb point k now: its own c and N_phi (Own: scatter) or its
    // material's, cohesion softened once it has yielded.
    template <bool Own> LPFDM_INLINE MohrStrength strength_of(const MaterialConstants& mc, std::size_t k) const;
    // eq. 12's look-up: the strain increments of the cell holding the lattice point (fx, fy)
    // (in cells), the mean of two or four cells where it lies on their common edge or
    // corner; cells outside `box` (the reference: the lattice; the fast kernel: the cells
    // whose strains it made, which hold every cell a moving node can reach) do not count.
    // False when no cell counts.
    LPFDM_INLINE bool strain_at(double fx, double fy, const Range& box, double& exx, double& eyy, double& exy, double& eyx) const;
    Range impose_supports();
    void carried_row(int j, int i0, int i1);
    Modes modes_;
    Kernel kernel_ = Kernel::Fast;
    int team_ = 1;  // threads, fixed when the Simulation is made
    bool profiling_ = false;
    double phase_s_[kPhases] = {0, 0, 0, 0, 0};
    double return_s_ = 0;  // profiling: return_seconds()
    long returned_ = 0;
    bool wide_ = false;  // the AVX2 version of the point loop and lattice phases (LPFDM_WIDE)

    Scene sc_;
    int mx_ = 0, my_ = 0;
    double L_ = 0, invL_ = 0;
    std::vector<MaterialConstants> consts_;
    std::vector<Group> groups_;
    std::vector<const MaterialConstants*> group_consts_;  // per group, for the point loop
    bool mohr_groups_ = false;  // some group is Mohr-Coulomb (set where a model is set): the point loop's blocks
    bool no_user_groups_ = true;  // no group has a user's model: the blocks go four points at a time across cells
    void find_mohr_groups();
    std::vector<double> row_ke_, row_du_;               // per node row: kinetic energy (a fixed-order sum), largest increment
    std::vector<std::uint8_t> row_gained_;              // per node row: a node gained mass this step; made with the
                                                        // node masses (nodal_forces), read by eq. 12's fill (compensate)
    std::vector<UserModel> user_models_;
    Points p_;
    // nodes
    std::vector<double> dux_, duy_, fx_, fy_, nmass_, nmass_prev_;
    std::vector<std::uint8_t> fixed_;
    std::vector<std::int32_t> fixed_nodes_;   // ascending
    std::vector<std::int32_t> fixed_rows_;    // row j's fixed nodes: fixed_nodes_[fixed_rows_[j] .. fixed_rows_[j + 1] - 1]
    enum : std::uint8_t { kEdgeBottom = 1, kEdgeTop = 2, kEdgeLeft = 4, kEdgeRight = 8, kEdgeWall = 16 };  // kEdgeWall: near a wall's face
    std::vector<std::uint8_t> fixed_edges_;  // per cell: which of its edges are fixed across
    // Per column i (and row j): its left edge i L, and the bounds of x / L inside it, i and i + 1
    // (-1 in the last column, where x < X does not follow from x / L < m): read by the point
    // loop once per run instead of converted from integers.
    struct Span { double at, lo, hi; };
    std::vector<Span> cols_, rows_;
    // cells
    std::vector<double> cmass_, cvol_, svxx_, svyy_, svxy_;
    // WATER and LOAD (water_pass, load_forces): per group Kw / n (0: dry), k / gamma_w and n;
    // per cell the water points' sums (sum V, sum V p n / Kw, sum V k / gamma_w, the storage
    // sum V n / Kw) and the step's net inflow and outflow through drains and faces; per cell
    // its drained edges (kEdge*); per point the stored energy the flow took (summed in point
    // order); the points in the rows of cells below each row (water_pass's bands); per node
    // the step's LOAD force and whether it has one (load_nodes_ lists those nodes).
    using GroupWater = detail::GroupWater;
    std::vector<GroupWater> group_water_;
    std::vector<double> wv_, wp_, wk_, wc_, wnew_, wq_, wr_;  // (wq_: sum V n p / Kw, the cell's pressure: flows only when above 0; wnew_: Phi after the exchange)
    std::vector<double> wkc_, wphi_, wqx_, wqy_;  // water_flow's: each cell's k and Phi, the flux across its right and top edges
    std::vector<double> wde_;
    std::vector<long> water_rows_;
    std::vector<std::int32_t> water_cell_points_;
    std::vector<std::uint8_t> drain_edges_;
    double gamma_w_ = 0;
    double drained_ = 0;            // water that left through the drains [m^3/m] (entered: negative)
    double d_water_ = 0;            // the stored water energy the flow and the drains took out [J/m]
    double w_loads_ = 0, h_loads_ = 0;  // LOAD's work, trapezoidal like the walls'
    std::vector<double> load_fx_, load_fy_;
    std::vector<std::uint8_t> load_mark_;
    std::vector<std::int32_t> load_nodes_;
    double hydrostatic(const Material& m, double x, double y) const;
    void setup_water();
    void geostatic();
    void water_pass();
    void water_flow();
    void water_faces_row(int j);
    void load_forces();
    void load_work();
    // Strain increments of eq. 5a-5d and the rotation of eq. 5f per cell, one record per
    // cell: the point loop reads all six together (six arrays were six memory streams).
    struct CellStrain { double xx = 0, yy = 0, xy = 0, yx = 0, rc = 1, rs = 0; };
    std::vector<CellStrain> strain_;
    std::vector<double> hgx_, hgy_;                        // hourglass increment per cell (HOURGLASS only)
    // MAPPING SMOOTH only, per cell: sum w V (sigma - p) . r and sum w V r, r the offset of a
    // part's centre from the cell centre in cells, p = (sigma_xx + sigma_yy) / 2 (the forces'
    // share of the gradient's variation across the cell, and the centroid of its material)
    std::vector<double> shx_, shy_, smu_, smv_;
    std::vector<double> centroid_trace_;  // MAPPING SMOOTH: per cell, the trace of the increments' gradient at the material's centroid
    // ADVECT POINTS only: per cell, sum m (d - E r) and sum m E of the points that landed in
    // it (r from the cell centre).
    // One record per cell, not six arrays (six arrays starting at the same offset in their
    // pages were six memory streams that evicted one another).
    struct Carried { double px = 0, py = 0, qxx = 0, qxy = 0, qyx = 0, qyy = 0; };
    std::vector<Carried> carried_;
    // The threaded point pass only: per thread its chunk's cells, mass and list length
    // (the lists themselves are Points::listed).
    std::vector<Part> parts_;
    std::vector<Landing> landings_;
    // advance_parted: thread u's chunk of the points, chunk_at_[u] .. chunk_at_[u + 1] - 1,
    // for chunk_team_ threads; parts_known_: parts_ and landings_ hold the last pass's
    // chunks (from list_at) and the cells their points lie in now.
    std::vector<long> chunk_at_;
    [[maybe_unused]] int chunk_team_ = 0;  // (used with OpenMP only)
    bool parts_known_ = false;
    PartedPass parted_;
    // The fast kernel's record of where the lattice is active, kept beside the fields it
    // describes (the reference cycle visits everything and needs none of it): outside
    // these boxes the cell sums, strains, nodal masses, forces and increments are zero.
    Range occupied_;   // cells holding points after the last mapping
    Range strained_;   // cells whose strains strain_ holds for this step (eq. 12 reads no other)
    Range live_nodes_; // nodes that may hold a non-zero du
    std::vector<WallState> walls_;
    // The energy account (energy()): the increments eq. 13 started from (after eq. 12),
    // the wall nodes driven this step (their damping is not applied), the running sums.
    std::vector<double> dux_old_, duy_old_;
    // DAMPING WINDOW=t: each node's mean increment (follow_mean), dt / t; empty, 0 without it
    std::vector<double> mean_ux_, mean_uy_;
    double mean_beta_ = 0;
    // node n's mean increments, 0 without the window
    double mean_at(const std::vector<double>& m, std::size_t n) const { return m.empty() ? 0.0 : m[n]; }
    std::vector<std::uint8_t> driven_;
    std::vector<std::int32_t> driven_nodes_;
    // Walls on the points: the cells whose points the next point pass tests against the
    // walls' faces (fixed_edges_ bit kEdgeWall), and each fixed node's FIX cards (x, y).
    std::vector<std::int32_t> wall_cells_;
    void mark_wall_cells();
    void contact_side(WallState& ws, const Wall& spec) const;
    void support_work(std::size_t n, double b, double c, double f, double& w, double& h) const;
    void drive_embedded(WallState& ws, double ddx, double ddy, double& hw, Range& wall_nodes);
    bool empty_beyond(int i, int j, int di, int dj) const;
    bool hold_by_walls(double x0, double y0, double& x, double& y) const;
    struct FixOwner { std::int16_t x, y; };
    std::vector<FixOwner> fix_owner_;  // per entry of fixed_nodes_
    std::vector<double> fix_rx_, fix_ry_;
    struct EnergySums {
        double w_walls = 0, w_fixes = 0, w_gravity = 0, d_damping = 0;        // force x the step's mean increment
        double h_walls = 0, h_fixes = 0, h_gravity = 0, h_damping = 0;        // the last step's force x half its increment
        double kinetic = 0, peak_kinetic = 0;                                 // now, and the most it was
        double left_strain = 0, left_potential = 0, left_plastic = 0;         // of the points that left
        double strain0 = 0, potential0 = 0;                                   // before the first step
        double w_ground = 0, h_ground = 0, h_input = 0;                       // SHAKE: fixed nodes moved (h_ground), input traction (h_input)
        double d_absorb = 0, h_absorb = 0, w_held = 0, h_held = 0;            // ABSORB: dashpots; the reactions taken over
        double d_slip = 0;                                                    // ADVECT FLIP: the supports' slip (flip_slip)
        double w_shift = 0;                                                   // SHIFT: the potential energy of the moves apart
    } es_;
    void start_energy();
    void keep_increments(const Range& nodes);
    struct RowEnergy { double kin = 0, sbx = 0, sby = 0, scx = 0, scy = 0, wd = 0, hd = 0; };
    std::vector<RowEnergy> row_energy_;  // per node row: the energy account's sums (energy_row_terms)
    template <class Wide> LPFDM_INLINE void energy_row_terms(int j, int i0, int i1, Wide);
    void tally_energy(int j0, int j1);
    // Elastic and potential energy of point k.
    double strain_energy(std::size_t k) const;
    // The volume point k's stress works on: min(V, V0) as in eq. 8, or with ADVECT FLIP its
    // initial volume V0 (see flip_transfer).
    double energy_volume(std::size_t k) const { return energy_volume(k, p_.vol[k]); }
    // The same with point k's volume vol given.
    double energy_volume(std::size_t k, double vol) const;
    double potential_energy(std::size_t k) const { return -groups_[p_.group[k]].mass * (sc_.gravity_x * p_.x[k] + sc_.gravity_y * p_.y[k]); }
    // Earthquakes: ground motion (SHAKE) and absorbing edges (ABSORB); see dynamics_begin.
    using Ground = detail::GroundMotion;
    Ground ground_[2];                // x, y
    long shake_step_ = 0;             // the first step of the shaking (detail::start_step; 0 without SHAKE)
    // One dashpot per (node, edge cell) of an absorbing edge: its node's slot, the cell (it
    // acts while the cell holds mass), its coefficients rho c L / 2 in x and y [N s/m per m],
    // and those of a compliant base's input traction (twice them, on the bottom edge).
    struct Dashpot { std::int32_t slot, cell; double cx, cy, ix, iy; };
    std::vector<Dashpot> dashpots_;
    std::vector<std::int32_t> absorb_nodes_;                       // per slot: its node
    std::vector<std::uint8_t> released_;                           // per slot: the FIX directions it gives up at START
    std::vector<double> absorb_cx_, absorb_cy_, input_fx_, input_fy_, hold_fx_, hold_fy_;  // per slot
    std::vector<double> dashpot_fx_, dashpot_fy_;  // per slot: the dashpots' force in the step (absorb_work)
    void setup_dynamics();
    void ground_step(long n);
    void replay_ground();
    void dynamics_begin();
    // The directions (kFixX, kFixY) in which a rigid SHAKE moves the fixed nodes.
    std::uint8_t shaken_dirs() const {
        return std::uint8_t((ground_[0].rigid() ? kFixX : 0) | (ground_[1].rigid() ? kFixY : 0));
    }
    void absorb_increments();
    void absorb_work();
    long step_ = 0;
    long parked_ = 0;               // the points a face stopped in the steps before this one (parked())
    long held_ = 0;                 // the moves a fixed edge's nodes held (held())
    mutable detail::Tally parking_;  // ... in this one (stop_at_edges)
    mutable detail::Tally holding_;  // held_: the moves stop_at_edges took from the lattice's own motion in this step
    std::size_t departed_ = 0;
    double ke_ = 0, mass_in_ = 0, mass_out_ = 0, mass0_ = 0, rx_ = 0, ry_ = 0, max_du_ = 0;
    Range integrated_; // the nodes the last integrate() visited (unbalanced_ratio reads them)
};
}  // namespace lpfdm
#endif  // LPFDM_HPP

// The implementation. With LPFDM_INTERNALS alone, only its inline part: the equations and
// helpers (namespace detail) that a unit testing them calls, without the out-of-line
// definitions (each block of those under #if defined(LPFDM_IMPLEMENTATION)).
#if (defined(LPFDM_IMPLEMENTATION) || defined(LPFDM_INTERNALS)) && !defined(LPFDM_IMPLEMENTATION_DONE)
#define LPFDM_IMPLEMENTATION_DONE
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <type_traits>
#if defined(_OPENMP)
#include <omp.h>
#endif
#ifndef LPFDM_NO_IO
#include <cerrno>
#include <charconv>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <fmt/compile.h>
#include <fmt/format.h>
#endif
// Clang contracts a * b + c into a fused multiply-add by default (-ffp-contract=on), and
// rewrites such expressions even for a processor without one: the AVX2 lanes then differ
// from the one-point code (as in the sign of a NaN, tests/test_mohr.cpp). This header's
// code is compiled without contraction, as GCC does in ISO C++ mode; the includer's own
// code keeps its setting (pushed here, popped at the end of the header).
#if defined(__clang__)
#pragma float_control(push)
#pragma clang fp contract(off)
#endif

namespace lpfdm {

// ======================================================================================
// THE EQUATIONS
//
// Where the paper is open, the choices made here (each tested in tests/):
// * Nodal forces are the exact transpose of eq. 5 (virtual work), not the printed
//   eq. 9, whose node order [k-1], [k+1] is ambiguous: sum_a F[a].du[a] = -L^2 sig:deps.
// * The Jaumann rotation by eq. 5f's d_theta is applied as an exact orthogonal
//   rotation (Cayley form, no trigonometric call): stress invariants are preserved to
//   rounding. It equals the usual linearised update to first order in d_theta.
// * Eq. 8 divides sum V sigma by max(L^2, sum V): identical to the paper while the
//   points' volume fits the cell; where points crossing cell edges pack more than one
//   cell's volume into a cell, its smeared stress is their volume average instead of
//   an overcount (that overcount made cells stiffer in proportion to their number of
//   points, and errors grew under refinement: see tests/test_cycle.cpp).
// * In eq. 8 a point smears at most its initial volume m / rho_0. A point failing in
//   tension keeps dilating (53 times its volume was seen behind a wall pushed through
//   soil); its smeared stiffness grew with its volume while its mass did not, and the
//   run went unstable with the wall at rest. Compression is unaffected.
// * Eq. 14 uses sgn(0) = 0 and the compensated du; a node without mass has du = 0.
// * Point volume follows V <- V (1 + d_eps_xx + d_eps_yy); a rigid rotation keeps it.
// ======================================================================================

// Hooke's law for plane strain, eq. 6 for an elastic point: d_sig = D d_eps, d_sig_zz
// from the in-plane volume change. T: one value, or the lanes of a vector (four points of
// four cells; the same operations in every lane).
template <class T>
LPFDM_INLINE inline void elastic_change(const MaterialConstants& k, const T& xx, const T& yy, const T& xy, const T& yx, T& dxx, T& dyy, T& dxy, T& dzz) {
    dxx = k.a1 * xx + k.a2 * yy;
    dyy = k.a2 * xx + k.a1 * yy;
    dxy = k.G * (xy + yx);  // G gamma, eq. 5e
    dzz = k.a2 * (xx + yy);
}
inline Stress elastic_change(const MaterialConstants& k, const StrainIncrement& d) {
    Stress ds;
    elastic_change(k, d.xx, d.yy, d.xy, d.yx, ds.xx, ds.yy, ds.xy, ds.zz);
    return ds;
}
inline void elastic_increment(const MaterialConstants& k, const StrainIncrement& d, Stress& s) {
    const Stress ds = elastic_change(k, d);
    s.xx += ds.xx; s.yy += ds.yy; s.xy += ds.xy; s.zz += ds.zz;
}

// The energy account's one material formula: a : C^-1 : b for two stresses of the plane
// strain state (sigma_zz included), C the isotropic elasticity of the material
// (K = (a1 + 2 a2) / 3, G): p_a p_b / K + s_a : s_b / (2G), p the mean stress, s the
// deviator. Half of it with a = b is the elastic energy per unit volume; with a the
// corrected stress and b the correction a Mohr-Coulomb return removed it is the plastic
// work per unit volume of that step (a : d_eps^p, d_eps^p = C^-1 b).
// T: one value, or the lanes of a vector (the AVX2 point loop's record_yield). Products
// with 1/3, 1/K and 1/(2G) (taken once per material), not quotients: a plastic return
// records it at every yielding point, and four divisions cost more there than the return's
// own arithmetic.
template <class T>
LPFDM_INLINE inline void compliance_product(const MaterialConstants& k, const T& axx, const T& ayy, const T& axy, const T& azz,
                                            const T& bxx, const T& byy, const T& bxy, const T& bzz, T& out) {
    constexpr double third = 1.0 / 3;
    const T pa = (axx + ayy + azz) * third, pb = (bxx + byy + bzz) * third;
    const T dev = (axx - pa) * (bxx - pb) + (ayy - pa) * (byy - pb) + (azz - pa) * (bzz - pb) + 2 * axy * bxy;
    out = pa * pb * k.inv_K + dev * k.inv_2G;
}
inline double compliance_product(const MaterialConstants& k, const Stress& a, const Stress& b) {
    double out;
    compliance_product(k, a.xx, a.yy, a.xy, a.zz, b.xx, b.yy, b.xy, b.zz, out);
    return out;
}

// The rotation of eq. 5f as an exact orthogonal matrix (Cayley form, no trigonometry):
// the material turns by phi with tan(phi/2) = theta/2 (phi = theta to third order), so
// the stress components turn by 2 phi. Returns (cos 2phi, sin 2phi).
// T: one value, or the lanes of a vector (the same operations in every lane).
template <class T>
LPFDM_INLINE inline void jaumann_rotation(const T& d_theta, T& c2, T& s2) {
    const T t = 0.5 * d_theta, d = 1 / (1 + t * t);
    const T co = (1 - t * t) * d, si = 2 * t * d;
    c2 = co * co - si * si;
    s2 = 2 * si * co;
}
namespace detail {
// Code written once for one value (T = double) and for the lanes of a vector (see
// LPFDM_WIDE): v = p[0], or p[0 .. 3]. (Vectors go through references: a function
// returning one would have another ABI without AVX, GCC warns.)
// The store is an assignment to doubles, or to a vector of doubles aligned as a double
// (which may alias doubles, GCC and Clang), not a memcpy: GCC takes a memcpy's store for
// one that may change any object, and after each reloaded the pointers that the lattice
// phases' lambdas reach by reference.
template <class T>
LPFDM_INLINE inline void load(const double* p, T& v) { std::memcpy(&v, p, sizeof v); }
template <class T>
LPFDM_INLINE inline void store(double* p, const T& v) {
    if constexpr (std::is_same_v<T, double>) {
        *p = v;
    } else {
#if LPFDM_WIDE
        typedef double U __attribute__((vector_size(sizeof(T)), aligned(alignof(double))));
        *reinterpret_cast<U*>(p) = v;
#else
        std::memcpy(p, &v, sizeof v);
#endif
    }
}
// A type as a value (a lambda's argument that says which T to use).
template <class T> struct Tag { using type = T; };
}  // namespace detail

// eq. 5a-5d: the strain increments of the cell whose node [1] is n1 (nodes in rows of
// `row`; h = 1 / 2L) from the nodal increments ux, uy; T: one cell, or the lanes of a
// vector for the cells n1 .. n1 + 3 of a row.
template <class T>
LPFDM_INLINE inline void cell_strain(const double* ux, const double* uy, int n1, int row, double h, T& xx, T& yy, T& xy, T& yx) {
    const int n2 = n1 + 1, n3 = n1 + row, n4 = n3 + 1;
    T ux1, ux2, ux3, ux4, uy1, uy2, uy3, uy4;
    detail::load(ux + n1, ux1); detail::load(ux + n2, ux2); detail::load(ux + n3, ux3); detail::load(ux + n4, ux4);
    detail::load(uy + n1, uy1); detail::load(uy + n2, uy2); detail::load(uy + n3, uy3); detail::load(uy + n4, uy4);
    xx = (ux2 + ux4 - ux1 - ux3) * h;  // eq. 5a
    yy = (uy3 + uy4 - uy1 - uy2) * h;  // eq. 5b
    xy = (ux3 + ux4 - ux1 - ux2) * h;  // eq. 5c
    yx = (uy2 + uy4 - uy1 - uy3) * h;  // eq. 5d
}
// MAPPING SMOOTH: the gradient of the cell's bilinear increment field (nodes [1]..[4]
// with increments ux, uy) at (u, v), the place in the cell from node [1] in cells. It is
// the field's gradient averaged over any rectangle centred there (the field is bilinear),
// so a point's square sees GIMP's gradient, part by part. At the centre, u = v = 1/2,
// it is eq. 5a-5d.
inline StrainIncrement bilinear_gradient(const double ux[4], const double uy[4], double u, double v, double invL) {
    StrainIncrement e;
    e.xx = ((ux[1] - ux[0]) * (1 - v) + (ux[3] - ux[2]) * v) * invL;
    e.yy = ((uy[2] - uy[0]) * (1 - u) + (uy[3] - uy[1]) * u) * invL;
    e.xy = ((ux[2] - ux[0]) * (1 - u) + (ux[3] - ux[1]) * u) * invL;
    e.yx = ((uy[1] - uy[0]) * (1 - v) + (uy[3] - uy[2]) * v) * invL;
    return e;
}

inline StrainIncrement cell_strain(const double* ux, const double* uy, int n1, int row, double h) {
    StrainIncrement e;
    cell_strain(ux, uy, n1, row, h, e.xx, e.yy, e.xy, e.yx);
    return e;
}
// HOURGLASS (not in the paper): the checkerboard part h = (+1, -1, -1, +1)/4 of a cell's
// nodal increments, the one pattern eq. 5 cannot see.
template <class T>
LPFDM_INLINE inline void checkerboard_mode(const double* ux, const double* uy, int n1, int row, T& gx, T& gy) {
    const int n2 = n1 + 1, n3 = n1 + row, n4 = n3 + 1;
    T ux1, ux2, ux3, ux4, uy1, uy2, uy3, uy4;
    detail::load(ux + n1, ux1); detail::load(ux + n2, ux2); detail::load(ux + n3, ux3); detail::load(ux + n4, ux4);
    detail::load(uy + n1, uy1); detail::load(uy + n2, uy2); detail::load(uy + n3, uy3); detail::load(uy + n4, uy4);
    gx = 0.25 * (ux1 - ux2 - ux3 + ux4);
    gy = 0.25 * (uy1 - uy2 - uy3 + uy4);
}

// Rotates the in-plane stress with the material (Jaumann); invariants are kept exactly.
// T: one value, or the lanes of a vector (the same operations in every lane).
template <class T, class C>
LPFDM_INLINE inline void rotate_stress(T& xx, T& yy, T& xy, const C& c2, const C& s2) {
    const T pm = 0.5 * (xx + yy), a = 0.5 * (xx - yy), b = xy;
    const T ar = a * c2 - b * s2, br = a * s2 + b * c2;
    xx = pm + ar; yy = pm - ar; xy = br;
}
inline void rotate_stress(Stress& s, double c2, double s2) { rotate_stress(s.xx, s.yy, s.xy, c2, s2); }
// eq. 6's elastic trial: the old stress turned with the material (Jaumann, eq. 5f), then
// the elastic increment de added (what the reference's consult_model does by rotate_stress
// and elastic_increment). T: one value, or the lanes of a vector.
template <class T, class D, class C>
LPFDM_INLINE inline void elastic_trial(T& xx, T& yy, T& xy, T& zz, const D& de, const C& rc, const C& rs) {
    rotate_stress(xx, yy, xy, rc, rs);
    xx += de.xx; yy += de.yy; xy += de.xy; zz += de.zz;  // eq. 6
}

// The rest of the paper's equations, one function each, written once: the reference
// cycle (Simulation::step_reference) calls them one value at a time, the fast kernel
// calls the same functions, with T one value or the four lanes of an AVX2 register
// (the same operations in the same order in every lane: the same numbers bit for bit).

// eq. 7a/7b: where a point at (x0, y0) of the cell whose node [1] lies at (xi, yj) and
// moved by (ux1, uy1) goes: the affine map of the cell's strain about node [1].
template <class T>
LPFDM_INLINE inline void move_point_paper(const T& x0, const T& y0, const StrainIncrement& e, double xi, double yj, double ux1, double uy1, T& x, T& y) {
    const T dx = x0 - xi, dy = y0 - yj;
    x = x0 + e.xx * dx + e.xy * dy + ux1;
    y = y0 + e.yy * dy + e.yx * dx + uy1;
}
// MOTION CENTRE: the map of eq. 7a/7b about the cell centre, moved by the mean (umx, umy)
// of the four nodal increments (mirror-symmetric). d: the point's own increment.
// E: a StrainIncrement, or its four components in the lanes of vectors (four points of four
// cells, with C their cells' xi, yj, umx, umy in lanes too). The mean increment of nodes
// [1]..[4]: mean_of_four.
template <class T>
LPFDM_INLINE inline void mean_of_four(const T& u1, const T& u2, const T& u3, const T& u4, T& mean) { mean = 0.25 * (u1 + u2 + u3 + u4); }
template <class T, class E, class C>
LPFDM_INLINE inline void move_point_centre(const T& x0, const T& y0, const E& e, const C& xi, const C& yj, double L, const C& umx, const C& umy, T& x, T& y, T& dx_out, T& dy_out) {
    const T cx = (x0 - xi) - 0.5 * L, cy = (y0 - yj) - 0.5 * L;
    x = x0 + e.xx * cx + e.xy * cy + umx;
    y = y0 + e.yy * cy + e.yx * cx + umy;
    dx_out = e.xx * cx + e.xy * cy + umx;
    dy_out = e.yy * cy + e.yx * cx + umy;
}
// MOTION BILINEAR: the four nodal increments (ux[0..3], uy[0..3] of nodes [1]..[4])
// interpolated by the cell's bilinear shape functions, as in MPM.
template <class T>
LPFDM_INLINE inline void move_point_bilinear(const T& x0, const T& y0, double xi, double yj, double invL, const double* ux, const double* uy, T& x, T& y, T& dx_out, T& dy_out) {
    const T u = (x0 - xi) * invL, v = (y0 - yj) * invL;
    const T w1 = (1 - u) * (1 - v), w2 = u * (1 - v), w3 = (1 - u) * v, w4 = u * v;
    x = x0 + w1 * ux[0] + w2 * ux[1] + w3 * ux[2] + w4 * ux[3];
    y = y0 + w1 * uy[0] + w2 * uy[1] + w3 * uy[2] + w4 * uy[3];
    dx_out = w1 * ux[0] + w2 * ux[1] + w3 * ux[2] + w4 * ux[3];
    dy_out = w1 * uy[0] + w2 * uy[1] + w3 * uy[2] + w4 * uy[3];
}

// MAPPING SMOOTH, along one axis: a point's square spans [x - l, x + l] (2 l <= L, so at
// most two cells); its first cell a (of m), the fractions w[0], w[1] of the square in cells a
// and a + 1, and the centres c[0], c[1] of those parts. Parts outside the lattice are left
// out and the rest scaled to 1. Mirror-symmetric: the same numbers, mirrored, for L m - x.
inline void square_overlap(double x, double l, double L, int m, int& a, double w[2], double c[2]) {
    const double lo = x - l, hi = x + l;
    const double t = lo / L;
    a = int(t);
    a -= t < a;  // floor(t): int() truncates towards zero (a library call fewer: std::floor is one without SSE4.1)
    const double edge = (a + 1) * L;  // between the two cells
    if (hi <= edge) { w[0] = 1; w[1] = 0; c[0] = x; c[1] = 0; }
    else {
        w[0] = (edge - lo) / (hi - lo); w[1] = (hi - edge) / (hi - lo);
        c[0] = 0.5 * (lo + edge); c[1] = 0.5 * (edge + hi);
    }
    if (a < 0) { a = 0; w[0] = 1; w[1] = 0; c[0] = 0.5 * (0 + hi); }  // the part left of the lattice
    if (a >= m - 1 && w[1] > 0) { a = m - 1; w[0] = 1; w[1] = 0; c[0] = 0.5 * (lo + m * L); }  // right of it
}

namespace detail {
// MAPPING SMOOTH along one axis: a square whose parts lie in cells a and a + 1 (fractions
// w, centres c: square_overlap) weighs node a + n by S[n], the mean over the square of the
// node's linear shape function (GIMP's weight): the sum over the parts of w times the
// shape function at the part's centre. S[2] is 0 where the square lies in cell a alone.
// T: one value, or the lanes of a vector (four squares; smooth_lanes): a = a L and a1 =
// (a + 1) L, the two cells' left edges.
template <class T>
LPFDM_INLINE inline void axis_shape(const T& a, const T& a1, const T w[2], const T c[2], double invL, T S[3]) {
    const T u0 = (c[0] - a) * invL, u1 = (c[1] - a1) * invL;  // the parts' centres in their cells
    S[0] = w[0] * (1 - u0);
    S[1] = w[0] * u0 + w[1] * (1 - u1);
    S[2] = w[1] * u1;
}
inline void axis_shape(int a, const double w[2], const double c[2], double L, double invL, double S[3]) {
    axis_shape(a * L, (a + 1) * L, w, c, invL, S);
}
// MAPPING SMOOTH's strain of a square (smooth_strain): ux[m][n], uy[m][n] the increments of
// node a + n of row b + m, sx and sy axis_shape's weights, wx and wy the square's fractions
// in its two cells along each axis. Along each row the mean of ux, uy over the square's x
// (xs, ys) and of their gradients along x (xd, yd, a cell's difference over L being its
// field's gradient); across the rows the mean of those (eq. 5a's d(ux)/dx, eq. 5d's d(uy)/dx,
// and the motion) and their gradient along y (eq. 5b's d(uy)/dy, eq. 5c's d(ux)/dy). T: one
// value, or the lanes of a vector (four squares; smooth_lanes).
template <class T>
LPFDM_INLINE inline void mean_over(const T s[3], const T f[3], T& out) { out = s[0] * f[0] + s[1] * f[1] + s[2] * f[2]; }
template <class T>
LPFDM_INLINE inline void slope_over(const T w[2], const T f[3], double invL, T& out) { out = (w[0] * (f[1] - f[0]) + w[1] * (f[2] - f[1])) * invL; }
template <class T>
LPFDM_INLINE inline void square_strain(const T sx[3], const T sy[3], const T wx[2], const T wy[2], const T ux[3][3], const T uy[3][3], double invL,
                                       T& exx, T& eyy, T& exy, T& eyx, T& dx, T& dy) {
    T xs[3], xd[3], ys[3], yd[3];
    for (int m = 0; m < 3; ++m) {
        mean_over(sx, ux[m], xs[m]); mean_over(sx, uy[m], ys[m]);
        slope_over(wx, ux[m], invL, xd[m]); slope_over(wx, uy[m], invL, yd[m]);
    }
    mean_over(sy, xd, exx);          // eq. 5a's d(ux)/dx
    slope_over(wy, ys, invL, eyy);   // eq. 5b's d(uy)/dy
    slope_over(wy, xs, invL, exy);   // eq. 5c's d(ux)/dy
    mean_over(sy, yd, eyx);          // eq. 5d's d(uy)/dx
    mean_over(sy, xs, dx); mean_over(sy, ys, dy);  // the mean increment (MOTION BILINEAR)
}
}  // namespace detail

// eq. 8: the factor that turns a cell's sum V sigma into the stress the nodal forces
// use, already divided by 2L (b = +-1/2L): 1/L^2 (the paper) times L^2, or 1 / sum V
// where the points pack more than the cell's area (see the choices at the head of this section).
// (Vectors go out through references: a function returning one would have another ABI
// without AVX, GCC warns.)
template <class T>
LPFDM_INLINE inline void smear_weight(const T& sum_vol, double L2, double inv2L, T& w) {
    const T one = T{} + 1;
    w = inv2L * (sum_vol > L2 ? L2 / sum_vol : one);
}

// The nodal force from one cell (eq. 9 as the exact transpose of eq. 5, virtual work):
// F[a] = -L^2 (sigma_xx b_x[a] + sigma_xy b_y[a], sigma_xy b_x[a] + sigma_yy b_y[a]),
// b = (+-1, +-1) / 2L. Corner: which node [1]..[4] of the cell the node is. (xx, yy, xy):
// the cell's sum V sigma times smear_weight.
template <int Corner, class T>
LPFDM_INLINE inline void add_cell_force(const T& xx, const T& yy, const T& xy, T& fx, T& fy) {
    if constexpr (Corner == 1) { fx += xx + xy; fy += xy + yy; }       // b = (-1, -1)
    else if constexpr (Corner == 2) { fx += xy - xx; fy += yy - xy; }  // b = (+1, -1)
    else if constexpr (Corner == 3) { fx += xx - xy; fy += xy - yy; }  // b = (-1, +1)
    else { fx -= xx + xy; fy -= xy + yy; }                             // b = (+1, +1)
}

// eq. 12a/12b: the increment (ux, uy) a node carried belonged to material that has since
// strained by (exx, eyy, exy, eyx): compensated.
template <class T>
LPFDM_INLINE inline void compensate_increment(T& ux, T& uy, const T& exx, const T& eyy, const T& exy, const T& eyx) {
    const T cx = ux * (1 - exx) - uy * exy;  // eq. 12a
    const T cy = uy * (1 - eyy) - ux * eyx;  // eq. 12b
    ux = cx; uy = cy;
}
namespace detail {
#if LPFDM_WIDE
// Four doubles (and four lane masks) as GCC/Clang vectors: AVX2 registers inside a
// function built for AVX2.
// The lanes (i, j, k, l) of a and b side by side (0-3 of a, 4-7 of b).
#if defined(__clang__)
#define LPFDM_SHUFFLE(a, b, i, j, k, l) __builtin_shufflevector(a, b, i, j, k, l)
#else
#define LPFDM_SHUFFLE(a, b, i, j, k, l) __builtin_shuffle(a, b, ::lpfdm::detail::v4m{i, j, k, l})
#endif
// The sign bits of a comparison's mask (all ones or zero in each lane) folded to two, by
// an SSE2 instruction: what (m[0] & m[1] & m[2] & m[3]) != 0 takes seven for.
typedef long long v2m __attribute__((vector_size(16)));
typedef double v2d __attribute__((vector_size(16)));
LPFDM_INLINE inline int lane_signs(const v2m& a) { return __builtin_ia32_movmskpd(v2d(a)); }
LPFDM_INLINE inline void halves(const v4m& m, v2m& lo, v2m& hi) { std::memcpy(&lo, &m, sizeof lo); std::memcpy(&hi, reinterpret_cast<const char*>(&m) + sizeof lo, sizeof hi); }
// True when every lane of a comparison's mask is set.
LPFDM_INLINE inline bool all_lanes(const v4m& m) { v2m lo, hi; halves(m, lo, hi); return lane_signs(lo & hi) == 3; }
// The strains (xx, yy, xy, yx) of four cells in the lanes, from the first four doubles
// of each cell's record (r0 .. r3: xx yy xy yx, one cell each).
LPFDM_INLINE inline void transpose_strains(const v4d& r0, const v4d& r1, const v4d& r2, const v4d& r3, v4d& xx, v4d& yy, v4d& xy, v4d& yx) {
    const v4d t0 = LPFDM_SHUFFLE(r0, r1, 0, 4, 2, 6), t1 = LPFDM_SHUFFLE(r0, r1, 1, 5, 3, 7);  // xx xy, yy yx of 0 1
    const v4d t2 = LPFDM_SHUFFLE(r2, r3, 0, 4, 2, 6), t3 = LPFDM_SHUFFLE(r2, r3, 1, 5, 3, 7);  // of 2 3
    xx = LPFDM_SHUFFLE(t0, t2, 0, 1, 4, 5); xy = LPFDM_SHUFFLE(t0, t2, 2, 3, 6, 7);
    yy = LPFDM_SHUFFLE(t1, t3, 0, 1, 4, 5); yx = LPFDM_SHUFFLE(t1, t3, 2, 3, 6, 7);
}
// Bit l set when lane l of a comparison's mask is.
LPFDM_INLINE inline int lane_bits(const v4m& m) { v2m lo, hi; halves(m, lo, hi); return lane_signs(lo) | lane_signs(hi) << 2; }
// True when no lane of a comparison's mask is set.
LPFDM_INLINE inline bool none_of_lanes(const v4m& m) { v2m lo, hi; halves(m, lo, hi); return lane_signs(lo | hi) == 0; }
// a = |v| lane by lane (the sign bit cleared, as std::fabs does).
LPFDM_INLINE inline void abs_of(const v4d& v, v4d& a) { a = v4d(v4m(v) & 0x7fffffffffffffffLL); }
#endif
LPFDM_INLINE inline void abs_of(double v, double& a) { a = std::fabs(v); }
}  // namespace detail

// eq. 13-14: du(t + dt/2) = du(t - dt/2) + dt^2 / m (F - D), with local non-viscous
// damping D = alpha |F| sgn(du) and sgn(0) = 0, along one axis. With DAMPING WINDOW=t (an
// option), D = alpha |F| sgn(du - mean): mean, the node's own increment averaged over the
// last t seconds (follow_mean), 0 without it (the same bits: du - 0 is du).
//
// Why the option: eq. 14 removes energy where a node's motion reverses, which brings a
// scene to rest. A node that flows steadily while it vibrates (a specimen compressed at a
// constant speed, a slope creeping) never reverses, and D then pushes against the flow at
// every step, alpha times the mean |F| of the vibration: a body force that the scene's
// supports carry. In verify_psc.deck at 10 cells the wall read its force less the base
// reaction as exactly that sum (MAPPING SMOOTH: 102 N/m, 3.1 % of the load; with ADVECT
// FLIP 198 N/m; the paper's mapping 44 N/m, a node's increment in the plateau swinging
// between 0.2 and 1.1 times its mean with a period of about 30 steps). Taken about the
// mean, the damping acts on the vibration alone and a steady flow is not held back; at
// rest the mean falls to 0 and it is eq. 14. The window must outlast the vibration's
// period (tests/README.md measures windows of 2.4 and 1.2 ms alike on that deck).
template <class T>
LPFDM_INLINE inline void damped_increment(const T& u0, const T& f, const T& m, double dt2, double alpha, T& u, const T& mean = T{}) {
    const T zero{}, unit = zero + 1, d = u0 - mean;
    const T sgn = d > 0 ? unit : (d < 0 ? -unit : zero);
    T abs_f;
    detail::abs_of(f, abs_f);
    u = u0 + dt2 / m * (f - alpha * abs_f * sgn);  // eq. 13, 14
}
// DAMPING WINDOW=t: a node's mean increment takes dt / t (beta) of the way to the increment
// eq. 13 starts from, once a step, before eq. 14 reads it (an exponential mean over t).
template <class T>
LPFDM_INLINE inline void follow_mean(const T& u0, double beta, T& mean) { mean = mean + beta * (u0 - mean); }

// ======================================================================================
// MATERIALS
//
// Where the paper is open, the choices made here (each tested in tests/):
// * Mohr-Coulomb: FLAC's closed-form return (shear, tension, and both at the corner),
//   with sigma_zz among the principal stresses. A point that yields for the first time
//   is returned to its intact surface and from then on keeps (1 - SOFTEN) of its cohesion.
// * Scatter: c and phi per point from a truncated Gaussian (resampled when outside
//   c >= 0, 0 < phi < 90 deg), drawn from the project's own xoshiro256** stream with
//   its own logarithm and sine, so the same seed gives the same numbers everywhere.
// ======================================================================================
namespace detail {

// Deterministic log and sine from + - * / only, so that the scatter of strengths is
// the same on every machine and standard library (libm results may differ in the last bit).
inline double log_det(double x) {
    int e = 0;
    double m = std::frexp(x, &e);  // x = m 2^e, m in [0.5, 1)
    if (m < 0.70710678118654752440) { m *= 2; --e; }
    const double z = (m - 1) / (m + 1), z2 = z * z;  // log m = 2 atanh z, |z| < 0.172
    double term = z, sum = 0;
    for (int k = 1; k < 40; k += 2) { sum += term / k; term *= z2; }
    return 2 * sum + e * 0.69314718055994530942;
}

inline double sin_det(double x) {  // for |x| <= pi/2, Taylor series to rounding
    const double x2 = x * x;
    double term = x, sum = 0;
    for (int k = 1; k < 40; k += 2) { sum += term; term *= -x2 / ((k + 1) * (k + 2)); }
    return sum;
}

constexpr double kPi = 3.14159265358979323846;
inline double sin_deg(double deg) { return sin_det(deg * kPi / 180); }

// N = (1 + sin a)/(1 - sin a) of a friction or dilation angle in degrees.
inline double flow_number(double deg) {
    const double s = sin_deg(deg);
    return (1 + s) / (1 - s);
}
}  // namespace detail

// The project's own random stream: xoshiro256** seeded through splitmix64, and a
// written-out Marsaglia polar transform for normal deviates.
class Random {
public:
    explicit Random(std::uint64_t seed = 1) {
        for (auto& s : s_) {
            seed += 0x9E3779B97F4A7C15ull;
            std::uint64_t z = seed;
            z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
            z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
            s = z ^ (z >> 31);
        }
    }
    std::uint64_t next() {
        const std::uint64_t r = rotl(s_[1] * 5, 7) * 9, t = s_[1] << 17;
        s_[2] ^= s_[0]; s_[3] ^= s_[1]; s_[1] ^= s_[2]; s_[0] ^= s_[3];
        s_[2] ^= t; s_[3] = rotl(s_[3], 45);
        return r;
    }
    double uniform() { return double(next() >> 11) * 0x1.0p-53; }  // [0, 1)
    double normal() {
        if (has_spare_) { has_spare_ = false; return spare_; }
        double u, v, s;
        do {
            u = 2 * uniform() - 1;
            v = 2 * uniform() - 1;
            s = u * u + v * v;
        } while (s >= 1 || s == 0);
        const double f = std::sqrt(-2 * detail::log_det(s) / s);
        spare_ = v * f; has_spare_ = true;
        return u * f;
    }
    // Gaussian(mean, sd) resampled until inside [lo, hi] (lo_open: lo excluded).
    double truncated_normal(double mean, double sd, double lo, double hi, bool lo_open) {
        for (;;) {
            const double z = mean + sd * normal();
            if ((lo_open ? z > lo : z >= lo) && z < hi) return z;
        }
    }

private:
    static std::uint64_t rotl(std::uint64_t x, int k) { return (x << k) | (x >> (64 - k)); }
    std::uint64_t s_[4];
    double spare_ = 0;
    bool has_spare_ = false;
};

inline MaterialConstants constants_of(const Material& m) {
    MaterialConstants k;
    k.model = m.model;
    const double K = m.bulk(), G = m.shear();
    k.a1 = K + 4 * G / 3; k.a2 = K - 2 * G / 3; k.G = G; k.rho = m.rho;
    k.inv_K = 1 / ((k.a1 + 2 * k.a2) / 3); k.inv_2G = 1 / (2 * G);
    if (m.model == Model::MohrCoulomb) {
        k.c = m.c; k.n_phi = detail::flow_number(m.phi_deg); k.n_psi = detail::flow_number(m.psi_deg);
        k.sqrt_n_phi = std::sqrt(k.n_phi);
        k.tension = m.tension; k.soften = m.soften; k.scatter = m.scatter > 0;
    }
    return k;
}

// FLAC's Mohr-Coulomb correction of a trial stress (already elastic-updated). In
// principal space (sig_zz among the three) the elastic domain is bounded by six shear
// planes f_ij = sig_i - N_phi sig_j + 2c sqrt(N_phi) >= 0 (i the compressive side) and
// three tension planes sig_t - sig_i >= 0. A violated plane a is corrected along its
// non-associated flow m_a (shear: e_i - N_psi e_j, tension: -e_i):
//     sig = sig_trial + sum_a mu_a D m_a,   mu_a >= 0,   f_a(sig) = 0 on the active set.
// First FLAC's choice: the plane of sig1, sig3 (shear) or of sig3 (tension), decided by
// FLAC's h function, in closed form. Where that leaves another plane violated (the
// principal order changed: an edge, the shear-tension corner, the apex), the two or
// three planes meeting there are made active together and a 2x2 or 3x3 system gives
// the multipliers: still closed form, never an iteration.
namespace detail {
// The trial stress in principal space and the strength terms, shared by the elastic test
// and the correction.
struct MohrTrial {
    double np, two_c_sq, sig_t;  // N_phi, 2 c sqrt(N_phi), tension limit
    double a, r;                 // in-plane (sxx - syy) / 2 and radius of Mohr's circle
    double sig[3];               // p - r, p + r, sig_zz
};
// The tension limit: the apex c / tan(phi), or the cut-off if lower.
inline double tension_limit(double np, double two_c_sq, double tension) {
    double sig_t = std::numeric_limits<double>::infinity();
    if (np > 1) sig_t = two_c_sq / (np - 1);
    if (tension >= 0) sig_t = std::min(sig_t, tension);
    return sig_t;
}
// The elastic test, given t.np and t.two_c_sq: fills the principal part of t and returns
// true when s is inside every plane. With c >= 0 and a finite N_phi the tension limit is
// never negative (nor NaN), so a stress with no tensile principal value passes the
// tension planes without computing it (one division per point saved); t.sig_t is set
// whenever the test fails.
inline bool mohr_inside(MohrTrial& t, double tension, const Stress& s) {
    const double p = 0.5 * (s.xx + s.yy);
    t.a = 0.5 * (s.xx - s.yy);
    t.r = std::sqrt(t.a * t.a + s.xy * s.xy);
    t.sig[0] = p - t.r; t.sig[1] = p + t.r; t.sig[2] = s.zz;
    const double lo = std::min(t.sig[0], t.sig[2]), hi = std::max(t.sig[1], t.sig[2]);
    const bool shear_ok = lo - hi * t.np + t.two_c_sq >= 0;
    if (shear_ok && hi <= 0 && t.two_c_sq >= 0 && t.np < std::numeric_limits<double>::infinity()) return true;
    t.sig_t = tension_limit(t.np, t.two_c_sq, tension);
    return shear_ok && t.sig_t - hi >= 0;
}
inline MohrResult mohr_coulomb_correct(const MaterialConstants& k, const MohrStrength& st, const MohrTrial& t, Stress& s);
}  // namespace detail

// 2 c sqrt(N_phi), the shear planes' constant.
inline double two_c_sqrt_n(const MohrStrength& st) { return 2 * st.c * (st.sqrt_n_phi > 0 ? st.sqrt_n_phi : std::sqrt(st.n_phi)); }

// The elastic test, then the correction of a point that yields.
LPFDM_INLINE inline MohrResult mohr_coulomb_return(const MaterialConstants& k, const MohrStrength& st, Stress& s) {
    detail::MohrTrial t;
    t.np = st.n_phi;
    t.two_c_sq = two_c_sqrt_n(st);
    if (detail::mohr_inside(t, st.tension, s)) return {};
    return detail::mohr_coulomb_correct(k, st, t, s);
}

namespace detail {
// The trial's principal direction with new principal values sg (in-plane sg[0], sg[1];
// sg[2] = sigma_zz), written into s, which holds the trial: one division.
inline void mohr_to_xy(const MohrTrial& t, const double sg[3], Stress& s) {
    const double pn = 0.5 * (sg[1] + sg[0]), rn = 0.5 * (sg[1] - sg[0]);
    const double inv_r = 1 / t.r, c2 = t.r > 0 ? t.a * inv_r : 1.0, s2 = t.r > 0 ? s.xy * inv_r : 0.0;
    s.xx = pn + rn * c2; s.yy = pn - rn * c2; s.xy = rn * s2; s.zz = sg[2];
}

// FLAC's closed form: shear on (sig_i1, sig_i3) (shear_first) or tension on sig_i3 (i: the
// principal values in order, fs and ft the trial's shear and tension functions). Most
// corrections end here: true when the result violates no plane (to tol), with res and s.
inline bool mohr_closed_form(const MaterialConstants& k, const MohrStrength& st, const MohrTrial& t, const int (&i)[3], bool shear_first, double fs, double ft, double tol,
                             Stress& s, MohrResult& res) {
    const double a1 = k.a1, a2 = k.a2;
    double sg[3] = {t.sig[0], t.sig[1], t.sig[2]}, e1 = 0, e3 = 0;
    if (shear_first) {  // mu D (e1 - N_psi e3), mu = -fs / (n . D m)
        const double ns0 = st.n_psi;
        const double d1 = a1 - a2 * ns0, d2 = a2 * (1 - ns0), d3 = a2 - a1 * ns0;
        const double mu = -fs / (d1 - t.np * d3);
        sg[i[0]] += mu * d1; sg[i[1]] += mu * d2; sg[i[2]] += mu * d3;
        e1 = -mu; e3 = mu * ns0;
    } else {  // mu D (-e3), mu = -ft / a1
        const double mu = -ft / a1;
        sg[i[0]] -= mu * a2; sg[i[1]] -= mu * a2; sg[i[2]] -= mu * a1;
        e3 = mu;
    }
    const double lo = std::min(std::min(sg[0], sg[1]), sg[2]), hi = std::max(std::max(sg[0], sg[1]), sg[2]);
    if (!(lo - t.np * hi + t.two_c_sq >= -tol && t.sig_t - hi >= -tol)) return false;
    res.mode = shear_first ? MohrResult::Shear : MohrResult::Tension;
    res.d_gamma_p = std::fabs(e1 - e3);
    res.d_vol_p = e1 + e3;
    mohr_to_xy(t, sg, s);
    return true;
}

// The nine planes: f = n . sig + kk >= 0, flow m. Shear plane (i, j): n = e_i - N_phi
// e_j, m = e_i - N_psi e_j; tension plane i: n = m = -e_i. The components are the
// values e_i - N e_j takes (1 - N 0, 0 - N 1, 0 - N 0), written out per plane instead
// of looped over an identity table. Each plane is made when a set first holds
// it (most searches need two or three of the nine), and again for the second flow rule.
struct MohrSearch {
    struct Plane { double n[3], kk, m[3]; };
    double np, ns, two_c_sq, sig_t, a1, a2, tol, mu_min;
    const double* trial;
    int npl;
    Plane pl[9];
    // Per plane, once per flow rule: D m in principal space and f at the trial stress.
    double dmp[9][3], ftrial[9];
    unsigned made = 0;  // bit a: plane a made for this flow rule
    // The admissible set found: the stress, the multipliers and the planes.
    double best[3] = {0, 0, 0}, best_mu[3] = {0, 0, 0};
    int best_act[3] = {-1, -1, -1}, best_na = 0;

    static constexpr int kShear[6][2] = {{0, 1}, {0, 2}, {1, 0}, {1, 2}, {2, 0}, {2, 1}};  // (i, j), i the compressive side
    static int shear_plane(int i, int j) { return 2 * i + (j > i ? j - 1 : j); }  // kShear's index of (i, j)
    static double f_at(const Plane& q, const double sg[3]) { return q.n[0] * sg[0] + q.n[1] * sg[1] + q.n[2] * sg[2] + q.kk; }
    void plane(int a) {
        if (made >> a & 1) return;
        made |= 1u << a;
        Plane& q = pl[a];
        if (a < 6) {
            const double n_one = 1.0 - np * 0.0, n_neg = 0.0 - np * 1.0, n_zero = 0.0 - np * 0.0;
            const double m_one = 1.0 - ns * 0.0, m_neg = 0.0 - ns * 1.0, m_zero = 0.0 - ns * 0.0;
            const int i = kShear[a][0], j = kShear[a][1];
            q.n[0] = q.n[1] = q.n[2] = n_zero; q.n[i] = n_one; q.n[j] = n_neg;
            q.m[0] = q.m[1] = q.m[2] = m_zero; q.m[i] = m_one; q.m[j] = m_neg;
            q.kk = two_c_sq;
        } else {
            q.n[0] = q.n[1] = q.n[2] = q.m[0] = q.m[1] = q.m[2] = -0.0;
            q.n[a - 6] = q.m[a - 6] = -1.0;
            q.kk = sig_t;
        }
        const double d12 = a1 - a2, a2_tr = a2 * (q.m[0] + q.m[1] + q.m[2]);  // a2 trace(m)
        dmp[a][0] = a2_tr + d12 * q.m[0]; dmp[a][1] = a2_tr + d12 * q.m[1]; dmp[a][2] = a2_tr + d12 * q.m[2];
        ftrial[a] = f_at(q, trial);
    }
    // Solves the active set act[0..NA) and checks the result; true if admissible (kept in
    // best*). NA a constant, so that the 1x1 and 2x2 systems tried most often run without
    // loop overhead.
    template <int NA> bool try_set(const int* act) {
        constexpr int na = NA;
        double A[3][3], b[3], mu[3] = {0, 0, 0};
        const double* dm[3];
        for (int u = 0; u < na; ++u) { plane(act[u]); dm[u] = dmp[act[u]]; }
        for (int u = 0; u < na; ++u) {
            b[u] = -ftrial[act[u]];
            for (int v = 0; v < na; ++v) A[u][v] = pl[act[u]].n[0] * dm[v][0] + pl[act[u]].n[1] * dm[v][1] + pl[act[u]].n[2] * dm[v][2];
        }
        // Gaussian elimination with partial pivoting on at most 3 x 3.
        for (int col = 0; col < na; ++col) {
            int piv = col;
            for (int row = col + 1; row < na; ++row) if (std::fabs(A[row][col]) > std::fabs(A[piv][col])) piv = row;
            if (std::fabs(A[piv][col]) < 1e-300) return false;
            std::swap(A[piv], A[col]); std::swap(b[piv], b[col]);
            for (int row = col + 1; row < na; ++row) {
                const double f = A[row][col] / A[col][col];
                for (int v = col; v < na; ++v) A[row][v] -= f * A[col][v];
                b[row] -= f * b[col];
            }
        }
        for (int u = na - 1; u >= 0; --u) {
            double acc = b[u];
            for (int v = u + 1; v < na; ++v) acc -= A[u][v] * mu[v];
            mu[u] = acc / A[u][u];
        }
        double sg[3] = {trial[0], trial[1], trial[2]};
        for (int u = 0; u < na; ++u) {
            if (mu[u] < mu_min) return false;
            for (int t = 0; t < 3; ++t) sg[t] += mu[u] * dm[u][t];
        }
        // Every plane at sg: the lowest shear plane is that of the smallest and the largest
        // principal value, the lowest tension plane that of the largest (for finite values
        // f_at gives the same numbers: its terms with a zero component are exact zeros).
        const double lo = std::min(std::min(sg[0], sg[1]), sg[2]), hi = std::max(std::max(sg[0], sg[1]), sg[2]);
        if (lo - np * hi + two_c_sq < -tol || (npl > 6 && sig_t - hi < -tol)) return false;
        for (int t = 0; t < 3; ++t) best[t] = sg[t];
        for (int u = 0; u < na; ++u) { best_mu[u] = mu[u]; best_act[u] = act[u]; }
        best_na = na;
        return true;
    }
    // The search itself (see mohr_coulomb_correct): the sets holding p0 first, with the
    // planes first[] before the others; then, for each flow rule, the other sets. The
    // mode of the return found, or Elastic when none is.
    MohrResult::Mode run(int p0, const int (&first)[3]);
};

inline MohrResult::Mode MohrSearch::run(int p0, const int (&first)[3]) {
    // The planes to join p0 in a set, in the order tried: first[], then the others.
    int partner[8], npartner = 0;
    if (p0 < npl) {
        for (int u = 0; u < 3; ++u)
            if (first[u] >= 0 && first[u] < npl && first[u] != p0) partner[npartner++] = first[u];
        for (int q = 0; q < npl; ++q)
            if (q != p0 && q != first[0] && q != first[1] && q != first[2]) partner[npartner++] = q;
    }
    bool found = false;
    MohrResult::Mode mode = MohrResult::Elastic;
    for (int pass = 0; pass < 2 && !found; ++pass) {
        if (pass == 1) { ns = np; made = 0; }  // the associated flow rule: the planes made again
        int act[3];
        // The sets holding p0: pairs, then triples (the apex), each set's planes sorted by index.
        for (int u = 0; u < npartner && !found; ++u) {
            act[0] = std::min(p0, partner[u]); act[1] = std::max(p0, partner[u]);
            found = try_set<2>(act);
        }
        for (int u = 0; u < npartner && !found; ++u)
            for (int v = u + 1; v < npartner && !found; ++v) {
                int x = p0, y = partner[u], z = partner[v];  // sorted: x < y < z
                if (x > y) std::swap(x, y);
                if (y > z) std::swap(y, z);
                if (x > y) std::swap(x, y);
                act[0] = x; act[1] = y; act[2] = z;
                found = try_set<3>(act);
            }
        if (found) { mode = MohrResult::Edge; break; }
        // The others: single planes, pairs, triples, each in index order.
        for (act[0] = 0; act[0] < npl && !found; ++act[0]) {
            if (found = try_set<1>(act), found) { mode = act[0] < 6 ? MohrResult::Shear : MohrResult::Tension; break; }
        }
        for (int na = 2; na <= 3 && !found; ++na) {
            for (act[0] = 0; act[0] < npl && !found; ++act[0])
                for (act[1] = act[0] + 1; act[1] < npl && !found; ++act[1]) {
                    if (act[0] == p0 || act[1] == p0) continue;
                    if (na == 2) { found = try_set<2>(act); continue; }
                    for (act[2] = act[1] + 1; act[2] < npl && !found; ++act[2])
                        if (act[2] != p0) found = try_set<3>(act);
                }
            if (found) mode = MohrResult::Edge;
        }
    }
    return mode;
}
}  // namespace detail

inline MohrResult detail::mohr_coulomb_correct(const MaterialConstants& k, const MohrStrength& st, const MohrTrial& t, Stress& s) {
    MohrResult res;
    const double np = t.np, two_c_sq = t.two_c_sq, sig_t = t.sig_t;
    // In-plane principal stresses about the current principal direction; index 2 is zz.
    const double* trial = t.sig;
    int i1 = 0, i2 = 1, i3 = 2;  // sig1 <= sig2 <= sig3
    if (trial[i1] > trial[i2]) std::swap(i1, i2);
    if (trial[i2] > trial[i3]) std::swap(i2, i3);
    if (trial[i1] > trial[i2]) std::swap(i1, i2);
    const double fs = trial[i1] - trial[i3] * np + two_c_sq, ft = sig_t - trial[i3];  // not both >= 0 here
    const double tol = 1e-11 * (std::fabs(trial[0]) + std::fabs(trial[1]) + std::fabs(trial[2]) + two_c_sq + (std::isfinite(sig_t) ? sig_t : 0));
    // FLAC's choice of plane by its h function, needed only when both planes are violated
    // (its square root is not paid otherwise).
    auto h_fn = [&]() {
        const double alpha_p = std::sqrt(1 + np * np) + np, sig_p = sig_t * np - two_c_sq;
        return trial[i3] - sig_t + alpha_p * (trial[i1] - sig_p);
    };
    const bool shear_first = fs < 0 && (ft >= 0 || !(h_fn() > 0));
    if (mohr_closed_form(k, st, t, {i1, i2, i3}, shear_first, fs, ft, tol, s, res)) return res;

    // The closed form was not admissible (the return crossed into another plane): a search
    // over the sets of one, two and three planes for the first admissible one. With psi < phi
    // the flow vectors can leave gaps between the regions they span near an edge, where no
    // non-associated return exists; there the associated one (a projection on a convex set,
    // which always exists) is used.
    // The search's order: first p0 (the closed form's plane, which the return crossed) with
    // each of the other planes, the most frequent first (for shear (i1, i3): the edge with
    // shear (i1, i2), the apex line with sig_i1's tension plane, the edge with (i2, i3); for
    // sig_i3's tension plane: the two shear planes of i3 and the other in-plane stress, or
    // of i3 and i1 when i3 is sig_zz); then the triples holding p0 (the apex, where all
    // nine planes meet when the tension limit is the apex), p0's other partners in the same
    // order; then the single planes, the other pairs and the other triples, each in index
    // order: every set holding FLAC's own plane before any set without it. In a flowing
    // collapse (decks/bench_flow.deck) 4 % of the point-updates search, and 94 % of the
    // searches end at the first or second set, instead of after the 9 single planes and up
    // to 36 pairs of the index order (about 240 ns per search); a return to the apex ends
    // among the first of p0's 28 triples, where the single planes and the other pairs before
    // them took it some fifty sets in. With psi = phi the
    // admissible sets give one stress (tests/test_mohr.cpp), and the order changes only its
    // round-off where two sets meet (the apex line lies on a shear and a tension plane);
    // with psi < phi they rarely (8 of 4.5 million searches in that collapse; 3 of 473 210
    // between the apex-first order and the one before it) give two
    // different returns, of which the one beside FLAC's own plane is taken. The AVX2 point
    // loop makes those first two sets four points at a time (detail::lanes::edge_return: the
    // same operations): a change to the search's order or arithmetic is a
    // change there.
    MohrSearch q;
    q.np = np; q.ns = st.n_psi; q.two_c_sq = two_c_sq; q.sig_t = sig_t; q.a1 = k.a1; q.a2 = k.a2; q.tol = tol;
    q.mu_min = -tol / (k.a1 + 1);
    q.trial = trial;
    q.npl = std::isfinite(sig_t) ? 9 : 6;
    const int p0 = shear_first ? MohrSearch::shear_plane(i1, i3) : 6 + i3;
    int first[3] = {-1, -1, -1};  // the planes to pair with p0 before the others, in order
    if (shear_first) { first[0] = MohrSearch::shear_plane(i1, i2); first[1] = 6 + i1; first[2] = MohrSearch::shear_plane(i2, i3); }
    else {  // sig_i3's tension plane: first the shear planes of i3 and the other in-plane stress (i1 if i3 is zz)
        const int o = i3 == 2 ? i1 : 1 - i3;
        first[0] = MohrSearch::shear_plane(o, i3); first[1] = MohrSearch::shear_plane(i3, o);
    }
    const MohrResult::Mode mode = q.run(p0, first);
    // The associated projection always exists, but within about 0.1 degree of phi = 90
    // (N_phi above 1e6) the tolerances fail and no set passes: the trial stress is kept.
    if (mode == MohrResult::Elastic) return res;
    res.mode = mode;
    // Plastic strains d_eps^p = -sum mu_a m_a (sig = sig_trial - D d_eps^p).
    double ep[3] = {0, 0, 0};
    for (int u = 0; u < q.best_na; ++u)
        for (int c = 0; c < 3; ++c) ep[c] -= q.best_mu[u] * q.pl[q.best_act[u]].m[c];
    res.d_gamma_p = std::max(std::max(ep[0], ep[1]), ep[2]) - std::min(std::min(ep[0], ep[1]), ep[2]);
    res.d_vol_p = ep[0] + ep[1] + ep[2];
    mohr_to_xy(t, q.best, s);
    return res;
}

#if defined(LPFDM_IMPLEMENTATION)  // out-of-line definitions (left out by LPFDM_INTERNALS alone)
template <bool Own> LPFDM_INLINE inline MohrStrength Simulation::strength_of(const MaterialConstants& mc, std::size_t k) const {
    const double c0 = Own ? p_.c0[k] : mc.c;
    MohrStrength st;
    st.n_phi = Own ? p_.n_phi[k] : mc.n_phi;
    st.sqrt_n_phi = Own ? p_.sqrt_n_phi[k] : mc.sqrt_n_phi;
    st.c = p_.yielded[k] ? c0 * (1 - mc.soften) : c0;
    st.n_psi = std::min(mc.n_psi, st.n_phi);
    st.tension = mc.tension;
    return st;
}

template <bool Own> LPFDM_INLINE inline void Simulation::mohr_consult(const MaterialConstants& mc, std::size_t k, double vol, Stress& s) {
    const Stress trial = s;
    const MohrResult r = mohr_coulomb_return(mc, strength_of<Own>(mc, k), s);
    if (r.mode != MohrResult::Elastic) record_yield(mc, k, vol, r.d_gamma_p, trial, s);
}

inline void Simulation::record_yield(const MaterialConstants& mc, std::size_t q, double vol, double d_gamma_p, const Stress& trial, const Stress& s) {
    p_.plastic_shear[q] += d_gamma_p;
    p_.yielded[q] = 1;  // softening takes effect from the next consult
    const Stress b{trial.xx - s.xx, trial.yy - s.yy, trial.xy - s.xy, trial.zz - s.zz};
    p_.plastic_work[q] += energy_volume(q, vol) * compliance_product(mc, s, b);
}

inline void Simulation::find_mohr_groups() {
    mohr_groups_ = false;
    no_user_groups_ = true;
    for (const MaterialConstants* mc : group_consts_) {
        mohr_groups_ = mohr_groups_ || mc->model == Model::MohrCoulomb;
        no_user_groups_ = no_user_groups_ && mc->model != Model::User;
    }
}

LPFDM_DEF void Simulation::set_user_model(int mat_id, UserModel f) {
    for (std::size_t m = 0; m < sc_.materials.size(); ++m) {
        if (sc_.materials[m].id != mat_id) continue;  // consts_ keeps its addresses: group_consts_ stays valid
        consts_[m].model = Model::User;
        consts_[m].user = int(user_models_.size());
        user_models_.push_back(std::move(f));
    }
    find_mohr_groups();
    modes_.plastic = true;
    modes_.user = true;
    modes_.threads_why = "a user's model runs on one thread";
    if (p_.plastic_shear.empty()) {
        p_.plastic_shear.assign(p_.size(), 0.0);
        p_.yielded.assign(p_.size(), 0);
        p_.plastic_work.assign(p_.size(), 0.0);
    }
}
#endif  // LPFDM_IMPLEMENTATION: the materials' members of Simulation

// ======================================================================================
// LATTICE AND POINTS
//
// Where the paper is open, the choices made here (each tested in tests/):
// * A point belongs to the cell floor(x/L), floor(y/L); the lattice is the half-open
//   box [0, mx L) x [0, my L). A point outside it has left: it is removed and its mass
//   is counted as outflow.
// * Point masses are rounded to multiples of one ulp of the total mass, so that every
//   mass sum is exact in double precision: mass inside + outflow == initial, bit for bit.
// ======================================================================================
namespace detail {

// Boxes select cells by their centres and nodes by their positions, with a tolerance of a
// thousandth of a cell, so a degenerate box selects a line. The index span [lo, hi] is
// clipped to the lattice (lo > hi: nothing); edges far outside are clamped before any
// conversion to int.
inline void cell_span(double a, double b, double L, int n, int& lo, int& hi) {
    const double tol = 1e-3 * L;
    lo = int(std::clamp(std::ceil((a - tol) / L - 0.5), 0.0, double(n)));
    hi = int(std::clamp(std::floor((b + tol) / L - 0.5), -1.0, double(n - 1)));
}
inline void node_span(double a, double b, double L, int n, int& lo, int& hi) {
    const double tol = 1e-3 * L;
    lo = int(std::clamp(std::ceil((a - tol) / L), 0.0, double(n + 1)));
    hi = int(std::clamp(std::floor((b + tol) / L), -1.0, double(n)));
}
// The nodes in box b, i0..i1 x j0..j1 (node_span on each axis; empty where i1 < i0 or j1 < j0).
inline void box_nodes(const Box& b, double L, int mx, int my, int& i0, int& i1, int& j0, int& j1) {
    node_span(b.x0, b.x1, L, mx, i0, i1);
    node_span(b.y0, b.y1, L, my, j0, j1);
}
// The nodes a wall drives: those in its box; a row or column of them (the box one line of
// nodes thick) reaches along its length to both nodes of every cell edge its segment
// covers, its ends rounded outward, so that the nodes hold its whole face (written from
// 1 cm above a smooth base, a column that stopped at the node above let the sand carry
// the base node through the face; Simulation::hold_by_walls). An end node a FIX or an
// earlier wall holds in a direction keeps that (validate checks the boxes as written).
inline void wall_span(const Box& b, double L, int mx, int my, int& i0, int& i1, int& j0, int& j1) {
    box_nodes(b, L, mx, my, i0, i1, j0, j1);
    if (i1 < i0 || j1 < j0) return;
    const double tol = 1e-3 * L;
    auto outward = [&](double a, double c, int n, int& lo, int& hi) {
        lo = int(std::clamp(std::floor((a + tol) / L), 0.0, double(n)));
        hi = int(std::clamp(std::ceil((c - tol) / L), 0.0, double(n)));
    };
    if (i0 == i1 && b.y1 > b.y0) outward(b.y0, b.y1, my, j0, j1);
    else if (j0 == j1 && b.x1 > b.x0) outward(b.x0, b.x1, mx, i0, i1);
}

// The most vertices a CLUSTER POLYGON may have: its check for a crossing takes n^2 / 2 steps.
inline constexpr std::size_t kMaxPolygonVertices = 10000;

// The cells a cluster fills, as runs: f(i0, i1, j) for cells i0..i1 of row j, each cell once,
// rows upwards. A box: the cells whose centres lie in it (cell_span). A polygon: the cells
// whose centres lie inside it (the even-odd rule along the row of centres) or within L/1000
// of it in x and in y (the square of half-side L/1000 about the centre touches an edge), so
// that a centre on an edge counts as inside and a polygon equal to a box fills the box's cells.
template <class F>
inline void cluster_cells(const Cluster& c, double L, int mx, int my, const F& f) {
    if (c.polygon.empty()) {
        int i0, i1, j0, j1;
        cell_span(c.box.x0, c.box.x1, L, mx, i0, i1);
        cell_span(c.box.y0, c.box.y1, L, my, j0, j1);
        if (i0 <= i1)
            for (int j = j0; j <= j1; ++j) f(i0, i1, j);
        return;
    }
    const std::vector<double>& v = c.polygon;
    const std::size_t n = v.size() / 2;
    if (n < 3) return;
    const double h = 1e-3 * L;
    struct Edge { double ax, ay, bx, by, ylo, yhi; };
    std::vector<Edge> edges;
    edges.reserve(n);
    double ylo = kHuge, yhi = -kHuge;
    for (std::size_t k = 0; k < n; ++k) {
        const std::size_t m = (k + 1) % n;
        const double ay = v[2 * k + 1], by = v[2 * m + 1];
        edges.push_back({v[2 * k], ay, v[2 * m], by, std::min(ay, by), std::max(ay, by)});
        ylo = std::min(ylo, ay);
        yhi = std::max(yhi, ay);
    }
    std::sort(edges.begin(), edges.end(), [](const Edge& a, const Edge& b) { return a.ylo < b.ylo; });
    int j0, j1;
    cell_span(ylo, yhi, L, my, j0, j1);
    std::vector<double> xs;
    std::vector<std::pair<int, int>> runs;
    auto run = [&](double a, double b) {  // the cells whose centres' x lies in [a, b]
        if (std::isnan(a) || std::isnan(b)) return;  // (a polygon of huge numbers, refused by validate)
        const int i0 = int(std::clamp(std::ceil(a / L - 0.5), 0.0, double(mx)));
        const int i1 = int(std::clamp(std::floor(b / L - 0.5), -1.0, double(mx - 1)));
        if (i0 <= i1) runs.push_back({i0, i1});
    };
    for (int j = j0; j <= j1; ++j) {
        const double yc = (j + 0.5) * L;
        xs.clear();
        runs.clear();
        for (const Edge& e : edges) {
            if (e.ylo > yc + h) break;
            if (e.yhi < yc - h) continue;
            if ((e.ay > yc) != (e.by > yc)) xs.push_back(e.ax + (yc - e.ay) * (e.bx - e.ax) / (e.by - e.ay));
            double xa = e.ax, xb = e.bx;  // the part of the edge within h of the row
            if (e.ay != e.by) {
                double t0 = (yc - h - e.ay) / (e.by - e.ay), t1 = (yc + h - e.ay) / (e.by - e.ay);
                if (t0 > t1) std::swap(t0, t1);
                if (t0 > 0) xa = e.ax + t0 * (e.bx - e.ax);
                if (t1 < 1) xb = e.ax + t1 * (e.bx - e.ax);
            }
            run(std::min(xa, xb) - h, std::max(xa, xb) + h);
        }
        std::sort(xs.begin(), xs.end());
        for (std::size_t k = 0; k + 1 < xs.size(); k += 2) run(xs[k], xs[k + 1]);
        std::sort(runs.begin(), runs.end());
        for (std::size_t k = 0; k < runs.size();) {
            int a = runs[k].first, b = runs[k].second;
            for (++k; k < runs.size() && runs[k].first <= b + 1; ++k) b = std::max(b, runs[k].second);
            f(a, b, j);
        }
    }
}

// The points the clusters make, in the order they are made: f(i, j, k, si, sj) for the
// point (si, sj) of the PPC x PPC of cluster k in cell (i, j), at ((i + (si + 0.5) / PPC) L,
// (j + (sj + 0.5) / PPC) L); cells row by row upwards, in a cell the clusters in deck order,
// then sj, si. A FILL=CELLS cluster makes all PPC^2 in each cell whose centre it holds
// (cluster_cells); a FILL=POINTS cluster those whose own positions it holds (cluster_cells
// on the lattice of its points, spacing L / PPC). A later cluster replaces an earlier one
// where it holds a point's place: a FILL=CELLS cluster in its cells, whole; a FILL=POINTS
// cluster at the positions it holds on the earlier point's own lattice (so that two
// polygons of one PPC sharing an edge make each point once, and none is lost).
template <class F>
inline void made_points(const std::vector<Cluster>& cs, double L, int mx, int my, const F& f) {
    const int nc = int(cs.size());
    auto fits = [&](int n) { return n >= 1 && n <= 32 && double(mx) * n <= 2e9 && double(my) * n <= 2e9; };  // (a scene not yet validated)
    std::vector<int> whole(std::size_t(mx) * std::size_t(my), -1);  // the last FILL=CELLS cluster of each cell
    std::vector<int> by_points;  // the FILL=POINTS clusters, in deck order
    for (int k = 0; k < nc; ++k) {
        if (cs[std::size_t(k)].fill_points) { by_points.push_back(k); continue; }
        cluster_cells(cs[std::size_t(k)], L, mx, my, [&](int i0, int i1, int j) {
            for (int i = i0; i <= i1; ++i) whole[std::size_t(j) * std::size_t(mx) + std::size_t(i)] = k;
        });
    }
    if (by_points.empty()) {  // every cluster fills cells: the last one holding a centre, all its points
        for (int j = 0; j < my; ++j)
            for (int i = 0; i < mx; ++i) {
                const int w = whole[std::size_t(j) * std::size_t(mx) + std::size_t(i)];
                const int n = w < 0 ? 0 : cs[std::size_t(w)].ppc;
                if (!fits(n)) continue;
                for (int sj = 0; sj < n; ++sj)
                    for (int si = 0; si < n; ++si) f(i, j, w, si, sj);
            }
        return;
    }
    // held[k][n]: the positions of the lattice of spacing L / n that the FILL=POINTS cluster k
    // holds, as runs of columns in its rows j0 .. j0 + first.size() - 2 (row j's runs
    // first[j - j0] .. first[j - j0 + 1]), for each n a cluster up to k uses
    struct Runs {
        int j0 = 0;
        std::vector<std::size_t> first;
        std::vector<std::pair<int, int>> run;
        bool holds(int i, int j) const {
            const long r = long(j) - j0;
            if (r < 0 || r + 1 >= long(first.size())) return false;
            for (std::size_t q = first[std::size_t(r)]; q < first[std::size_t(r) + 1]; ++q)
                if (run[q].first <= i && i <= run[q].second) return true;
            return false;
        }
    };
    std::vector<std::vector<Runs>> held(cs.size());
    for (int k : by_points) {
        held[std::size_t(k)].resize(33);
        for (int e = 0; e <= k; ++e) {
            const int n = cs[std::size_t(e)].ppc;
            if (!fits(n) || !held[std::size_t(k)][std::size_t(n)].first.empty()) continue;
            Runs& h = held[std::size_t(k)][std::size_t(n)];
            std::vector<int> rows;  // each run's row (upwards: cluster_cells' order)
            cluster_cells(cs[std::size_t(k)], L / n, mx * n, my * n, [&](int i0, int i1, int j) {
                h.run.push_back({i0, i1});
                rows.push_back(j);
            });
            h.first.assign(1, 0);
            if (rows.empty()) continue;
            h.j0 = rows.front();
            h.first.assign(std::size_t(rows.back() - h.j0) + 2, 0);
            for (int j : rows) ++h.first[std::size_t(j - h.j0) + 1];
            for (std::size_t q = 1; q < h.first.size(); ++q) h.first[q] += h.first[q - 1];
        }
    }
    for (int j = 0; j < my; ++j)
        for (int i = 0; i < mx; ++i) {
            const int w = whole[std::size_t(j) * std::size_t(mx) + std::size_t(i)];
            // the clusters that may make points here: w (a FILL=CELLS one) and the FILL=POINTS ones after it
            auto in_cell = [&](int k) {
                const Cluster& c = cs[std::size_t(k)];
                const int n = c.ppc;
                if (!fits(n)) return;
                const auto later = std::upper_bound(by_points.begin(), by_points.end(), k);
                for (int sj = 0; sj < n; ++sj)
                    for (int si = 0; si < n; ++si) {
                        const int pi = i * n + si, pj = j * n + sj;  // the point's place on the lattice of spacing L / n
                        if (c.fill_points && !held[std::size_t(k)][std::size_t(n)].holds(pi, pj)) continue;
                        bool replaced = false;
                        for (auto q = later; q != by_points.end() && !replaced; ++q) replaced = held[std::size_t(*q)][std::size_t(n)].holds(pi, pj);
                        if (!replaced) f(i, j, k, si, sj);
                    }
            };
            auto q = std::upper_bound(by_points.begin(), by_points.end(), w);
            if (w >= 0) in_cell(w);
            for (; q != by_points.end(); ++q) in_cell(*q);
        }
}

// Which cluster fills each cell of an mx x my lattice, cell (i, j) at j mx + i: the index
// in `clusters` of the last that fills it (a later cluster replaces an earlier one), -1 for
// none.
// The warnings that read this map (opening_warnings, fos_warnings) skip a lattice of more
// cells than kWarnCells (its 4 bytes a cell, 200 MB, for a warning), as they skip one
// without a size.
constexpr double kWarnCells = 5e7;
inline bool warn_map_fits(const Scene& s) {
    return s.mx > 0 && s.my > 0 && s.cell_m > 0 && double(s.mx) * s.my <= kWarnCells;
}
inline std::vector<int> cluster_owners(const std::vector<Cluster>& clusters, double L, int mx, int my) {
    std::vector<int> owner(std::size_t(mx) * std::size_t(my), -1);
    const bool by_points = std::any_of(clusters.begin(), clusters.end(), [](const Cluster& c) { return c.fill_points; });
    if (by_points) {  // a cell partly full: the last cluster that makes a point in it (made_points)
        made_points(clusters, L, mx, my, [&](int i, int j, int k, int, int) { owner[std::size_t(j) * std::size_t(mx) + std::size_t(i)] = k; });
        return owner;
    }
    for (std::size_t ci = 0; ci < clusters.size(); ++ci)
        cluster_cells(clusters[ci], L, mx, my, [&](int i0, int i1, int j) {
            for (int i = i0; i <= i1; ++i) owner[std::size_t(j) * std::size_t(mx) + std::size_t(i)] = int(ci);
        });
    return owner;
}

// What is wrong with the shape of a polygon (its vertices x1 y1 x2 y2 ...), or "" if
// nothing; `at` is the index in v of the coordinate to report it at (v.size(): the polygon
// as a whole). In this order: x y pairs, at least 3 and at most kMaxPolygonVertices of
// them, no vertex the same as the one before it (the last the same as the first), not all on
// one line (no area), and no edge touching an earlier one but at a vertex they share (nor
// running back along it): a polygon that crosses itself is reported at the end of the first
// edge that does (the edge from the last vertex back to the first: at the last).
inline std::string polygon_problem(const std::vector<double>& v, std::size_t& at) {
    const std::size_t n = v.size() / 2;
    at = v.size();
    auto name = [](std::size_t k) { return "vertex " + std::to_string(k + 1); };
    auto point = [&](std::size_t k) { return "(" + shortest(v[2 * k]) + ", " + shortest(v[2 * k + 1]) + ")"; };
    if (v.size() % 2) {
        at = v.size() - 1;
        return name(n) + " has an x but no y: a polygon takes x y pairs (" + std::to_string(v.size()) + " numbers given)";
    }
    if (n < 3) return "a polygon needs at least 3 vertices (x y pairs); this one has " + std::to_string(n);
    if (n > kMaxPolygonVertices) {
        at = 2 * kMaxPolygonVertices;
        return "a polygon may have at most " + std::to_string(kMaxPolygonVertices) + " vertices; this one has " + std::to_string(n);
    }
    for (std::size_t k = 0; k < n; ++k) {
        const std::size_t m = (k + 1) % n;
        if (v[2 * k] != v[2 * m] || v[2 * k + 1] != v[2 * m + 1]) continue;
        if (m == 0) {
            at = 2 * k;
            return "the last vertex " + point(k) + " repeats the first: a polygon closes by itself";
        }
        at = 2 * m;
        return name(m) + " " + point(m) + " repeats the vertex before it";
    }
    const double ax = v[0], ay = v[1];
    std::size_t far = 1;
    for (std::size_t k = 1; k < n; ++k)
        if (std::hypot(v[2 * k] - ax, v[2 * k + 1] - ay) > std::hypot(v[2 * far] - ax, v[2 * far + 1] - ay)) far = k;
    const double ux = v[2 * far] - ax, uy = v[2 * far + 1] - ay;
    bool flat = true;
    for (std::size_t k = 1; k < n && flat; ++k)
        flat = std::fabs(ux * (v[2 * k + 1] - ay) - uy * (v[2 * k] - ax)) <= 1e-12 * (ux * ux + uy * uy);
    if (flat) return "the polygon has no area: its vertices lie on one line";
    auto orient = [&](std::size_t a, std::size_t b, std::size_t c) {
        const double d = (v[2 * b] - v[2 * a]) * (v[2 * c + 1] - v[2 * a + 1]) - (v[2 * b + 1] - v[2 * a + 1]) * (v[2 * c] - v[2 * a]);
        return (d > 0) - (d < 0);
    };
    auto between = [&](std::size_t a, std::size_t b, std::size_t c) {  // c, on the line ab, lies on the segment
        return std::min(v[2 * a], v[2 * b]) <= v[2 * c] && v[2 * c] <= std::max(v[2 * a], v[2 * b]) &&
               std::min(v[2 * a + 1], v[2 * b + 1]) <= v[2 * c + 1] && v[2 * c + 1] <= std::max(v[2 * a + 1], v[2 * b + 1]);
    };
    auto edge = [&](std::size_t k) {
        const std::size_t m = (k + 1) % n;
        return m == 0 ? "the edge from " + name(k) + " back to vertex 1" : "the edge from " + name(k) + " to " + name(m);
    };
    for (std::size_t k = 1; k < n; ++k) {
        const std::size_t a = k, b = (k + 1) % n;
        for (std::size_t e = 0; e < k; ++e) {
            const std::size_t c = e, d = e + 1;
            bool meets;
            if (d == a || (b == c)) {  // neighbours: they meet at their shared vertex; do they overlap?
                const std::size_t s = d == a ? a : b, p = d == a ? c : d, q = d == a ? b : a;
                meets = orient(s, p, q) == 0 && (v[2 * p] - v[2 * s]) * (v[2 * q] - v[2 * s]) + (v[2 * p + 1] - v[2 * s + 1]) * (v[2 * q + 1] - v[2 * s + 1]) > 0;
            } else {
                const int o1 = orient(a, b, c), o2 = orient(a, b, d), o3 = orient(c, d, a), o4 = orient(c, d, b);
                meets = (o1 * o2 < 0 && o3 * o4 < 0) || (o1 == 0 && between(a, b, c)) || (o2 == 0 && between(a, b, d)) ||
                        (o3 == 0 && between(c, d, a)) || (o4 == 0 && between(c, d, b));
            }
            if (!meets) continue;
            at = 2 * (b == 0 ? a : b);
            return "the polygon crosses itself: " + edge(k) + " " + (d == a || b == c ? "runs back along " : "meets ") + edge(e);
        }
    }
    return "";
}

// The cell centre nearest to a polygon (vertices x1 y1 x2 y2 ...; a box: its corners) and
// its distance from it. A cell centre lies within L of every point of the lattice.
inline void nearest_centre(const std::vector<double>& v, double L, int mx, int my, double& cx, double& cy, double& dist) {
    const std::size_t n = v.size() / 2;
    auto distance = [&](double px, double py) {
        double best = kHuge;
        for (std::size_t k = 0; k < n; ++k) {
            const std::size_t m = (k + 1) % n;
            const double ax = v[2 * k], ay = v[2 * k + 1], ex = v[2 * m] - ax, ey = v[2 * m + 1] - ay;
            const double ee = ex * ex + ey * ey;
            const double t = ee > 0 ? std::clamp(((px - ax) * ex + (py - ay) * ey) / ee, 0.0, 1.0) : 0.0;
            best = std::min(best, std::hypot(px - ax - t * ex, py - ay - t * ey));
        }
        return best;
    };
    dist = kHuge;
    cx = cy = 0;
    for (std::size_t k = 0; k < n; ++k) {
        const std::size_t m = (k + 1) % n;
        const double ax = v[2 * k], ay = v[2 * k + 1], bx = v[2 * m], by = v[2 * m + 1];
        int j0, j1;
        cell_span(std::min(ay, by) - L, std::max(ay, by) + L, L, my, j0, j1);
        for (int j = j0; j <= j1; ++j) {
            const double yc = (j + 0.5) * L;
            double xa = ax, xb = bx;  // the part of the edge within L of the row
            if (ay != by) {
                double t0 = (yc - L - ay) / (by - ay), t1 = (yc + L - ay) / (by - ay);
                if (t0 > t1) std::swap(t0, t1);
                if (t0 > 0) xa = ax + t0 * (bx - ax);
                if (t1 < 1) xb = ax + t1 * (bx - ax);
            }
            int i0, i1;
            cell_span(std::min(xa, xb) - L, std::max(xa, xb) + L, L, mx, i0, i1);
            for (int i = i0; i <= i1; ++i) {
                const double px = (i + 0.5) * L, d = distance(px, yc);
                if (d < dist || (d == dist && (yc < cy || (yc == cy && px < cx)))) { dist = d; cx = px; cy = yc; }
            }
        }
    }
}
}  // namespace detail
#if defined(LPFDM_IMPLEMENTATION)  // out-of-line definitions (left out by LPFDM_INTERNALS alone)

// Whether the points of scene s hold the arrays of use u (threads: the run has more than
// one thread).
inline bool uses(const Scene& s, Points::Use u, bool threads) {
    bool plastic = false, scatter = false;
    for (const auto& m : s.materials) {
        plastic |= m.model == Model::MohrCoulomb;
        scatter |= m.scatter > 0;
    }
    switch (u) {
    case Points::kPlastic: return plastic;
    case Points::kScatter: return scatter;
    case Points::kThreads: return threads;
    case Points::kCarry: return threads && s.advect == Advect::Points;
    case Points::kFlip: return s.advect == Advect::Flip;
    case Points::kWater: return s.water.on;
    case Points::kLoad: return !s.loads.empty();
    default: return true;
    }
}

// Bytes the arrays of a scene will take (for the memory check before anything is allocated).
LPFDM_DEF double estimate_bytes(const Scene& s, double points) {
    const double cells = double(s.mx) * s.my, nodes = (s.mx + 1.0) * (s.my + 1.0);
    double per_point = 0;  // the arrays the scene's points will hold (threads' scratch counted: at most 4 bytes)
    Points().each_array([&](const char*, const auto& v, Points::Use u, bool) {
        if (uses(s, u, true)) per_point += double(sizeof(v[0]));
    });
    const double shift = s.shift ? (8 * 8 + 32 + 4) * cells : 0;  // SHIFT: four sub-cells and about four sub-nodes a cell, the guard's sums
    const double flip = s.advect == Advect::Flip ? (5 + 4) * 8 * nodes : 0;  // ADVECT FLIP: five arrays a node, and flip_sums' four
    const double smooth = s.mapping == Mapping::Smooth ? 12 * 8 * cells : 0;   // MAPPING SMOOTH: smear_lanes' twelve a cell
    return cells * (5 * 8 + 6 * 8) + nodes * (6 * 8 + 1) + points * (per_point + 2 * 8) + shift + flip + smooth;  // (+ the initial positions)
}

// The points the scene's clusters make (made_points): exact, or for a lattice too large to
// scan (or, with FILL=POINTS, too many places to test) an upper bound, the clusters'
// points summed, for the memory check.
LPFDM_DEF double count_points(const Scene& s) {
    if (s.mx <= 0 || s.my <= 0 || !(s.cell_m > 0)) return 0;
    double n = 0;
    const double cells = double(s.mx) * s.my;
    const bool by_points = std::any_of(s.clusters.begin(), s.clusters.end(), [](const Cluster& c) { return c.fill_points; });
    int most = 1;  // the largest PPC
    for (const auto& c : s.clusters) most = std::max(most, std::clamp(c.ppc, 1, 32));
    // Too large to scan (or, with FILL=POINTS, to test each place): an upper bound is
    // enough for the memory check.
    if (cells > 5e7 || (by_points && cells * most * most > 2e8)) {
        for (const auto& c : s.clusters) {
            double cells_in = (c.box.x1 - c.box.x0) * (c.box.y1 - c.box.y0) / (s.cell_m * s.cell_m);
            if (c.ppc < 1 || c.ppc > 32) continue;  // (a scene not yet validated)
            if (c.fill_points && double(s.mx) * c.ppc <= 2e9 && double(s.my) * c.ppc <= 2e9) {  // its points, one a cell of the lattice of spacing L / PPC
                double in = 0;
                detail::cluster_cells(c, s.cell_m / c.ppc, s.mx * c.ppc, s.my * c.ppc, [&](int i0, int i1, int) { in += i1 - i0 + 1; });
                n += in;
                continue;
            }
            if (!c.polygon.empty()) {
                cells_in = 0;
                detail::cluster_cells(c, s.cell_m, s.mx, s.my, [&](int i0, int i1, int) { cells_in += i1 - i0 + 1; });
            }
            n += cells_in * c.ppc * c.ppc;
        }
        return n;
    }
    if (by_points) {
        detail::made_points(s.clusters, s.cell_m, s.mx, s.my, [&](int, int, int, int, int) { n += 1; });
        return n;
    }
    const std::vector<int> owner = detail::cluster_owners(s.clusters, s.cell_m, s.mx, s.my);  // (a cell's points at once)
    for (int o : owner)
        if (o >= 0) n += double(s.clusters[std::size_t(o)].ppc) * s.clusters[std::size_t(o)].ppc;
    return n;
}

// The same scene on a lattice k times finer: same geometry in metres, dt / k, and k
// times the steps and output intervals, so that the same model time is covered.
LPFDM_DEF void refine(Scene& s, int k) {
    s.mx *= k; s.my *= k; s.cell_m /= k; s.dt_s /= k; s.steps *= k;
    for (auto& o : s.outputs) o.every *= k;
}
LPFDM_DEF Modes modes_of(const Scene& s, Kernel asked) {
    Modes m;
    m.mapping = s.mapping;
    m.motion = s.motion != Motion::Default ? s.motion : s.mapping == Mapping::Smooth ? Motion::Bilinear : Motion::Centre;
    m.advect = s.advect;
    m.hourglass = s.hourglass > 0;
    m.dynamic = !s.shakes.empty() || s.absorb != 0;
    m.shake = !s.shakes.empty();
    m.water = s.water.on;
    m.loads = !s.loads.empty() || s.reservoir.on;
    for (const auto& mat : s.materials) {
        m.plastic |= mat.model == Model::MohrCoulomb;
        m.scatter |= mat.scatter > 0;
    }
    m.kernel = asked;
    // The AVX2 point loop follows the default modes only (choose_point_loop); MAPPING
    // SMOOTH's has lanes of its own (smooth_lanes).
    if (m.kernel == Kernel::Fast)
        m.points_why = m.mapping == Mapping::Smooth && m.motion == Motion::Bilinear ? "MAPPING SMOOTH: its sums a point at a time (a cell's side by side), the rest four points at a time"
                       : m.mapping == Mapping::Smooth ? "MAPPING SMOOTH with MOTION PAPER or CENTRE: AVX2 for the Mohr-Coulomb consult only"
                       : m.advect == Advect::Points ? "ADVECT POINTS has no AVX2 point loop"
                       : m.motion == Motion::Paper  ? "MOTION PAPER has no AVX2 point loop"
                       : m.motion == Motion::Bilinear ? "MOTION BILINEAR has no AVX2 point loop" : "";
    return m;
}

// The unit of the implementation.
namespace detail {
LPFDM_DEF int define_LPFDM_IMPLEMENTATION_in_one_unit() { return 1; }
}  // namespace detail

LPFDM_DEF Simulation::Simulation(const Scene& scene, Kernel kernel, int) : modes_(modes_of(scene, kernel)), sc_(scene) {
    kernel = kernel_ = modes_.kernel;
    sc_.motion = modes_.motion;
    wide_ = kernel == Kernel::Fast && have_wide();
#if defined(_OPENMP)
    if (kernel != Kernel::Reference) team_ = std::max(1, std::min(omp_get_max_threads(), omp_get_thread_limit()));
#endif
    setup();
    choose_point_loop();
}

inline void Simulation::setup() {
    mx_ = sc_.mx; my_ = sc_.my; L_ = sc_.cell_m; invL_ = 1 / L_;
    const std::size_t nodes = std::size_t(mx_ + 1) * (my_ + 1), cells = std::size_t(mx_) * my_;
    for (auto* v : {&dux_, &duy_, &fx_, &fy_, &nmass_, &nmass_prev_, &dux_old_, &duy_old_}) v->assign(nodes, 0.0);
    if (sc_.damping_window > 0 && largest_damping(sc_) > 0) {  // DAMPING WINDOW=t
        for (auto* v : {&mean_ux_, &mean_uy_}) v->assign(nodes, 0.0);
        mean_beta_ = sc_.dt_s / sc_.damping_window;
    }
    if (modes_.advect == Advect::Flip) {
        for (auto* v : {&flip_mass_, &flip_ax_, &flip_ay_, &flip_sx_, &flip_sy_}) v->assign(nodes, 0.0);
        if (LPFDM_WIDE && kernel_ != Kernel::Reference) flip_rec_.assign(4 * nodes + 4, 0.0);  // (flip_sums: with AVX2)
    }
    fixed_.assign(nodes, 0);
    driven_.assign(nodes, 0);
    for (auto* v : {&cmass_, &cvol_, &svxx_, &svyy_, &svxy_}) v->assign(cells, 0.0);
    strain_.assign(cells, CellStrain{});
    auto spans = [&](int m, std::vector<Span>& v) {
        v.resize(std::size_t(m));
        for (int i = 0; i < m; ++i) v[std::size_t(i)] = Span{i * L_, double(i), i + 1 < m ? double(i + 1) : -1.0};
    };
    spans(mx_, cols_);
    spans(my_, rows_);
    if (modes_.hourglass) { hgx_.assign(cells, 0.0); hgy_.assign(cells, 0.0); }
    if (modes_.mapping == Mapping::Smooth) for (auto* v : {&shx_, &shy_, &smu_, &smv_, &centroid_trace_}) v->assign(cells, 0.0);
    if (modes_.mapping == Mapping::Smooth) holds_point_.assign(cells, 0);
    if (sc_.shift) {  // SHIFT: the sub-cells and their nodes
        shift_fill_.assign(4 * cells, 0.0);
        shift_excess_.assign(std::size_t(2 * mx_ + 1) * std::size_t(2 * my_ + 1), 0.0);
        shift_cells_.assign(cells, ShiftCell{});
        shift_full_.assign(cells, 0);
    }
    if (modes_.advect == Advect::Points)
        carried_.assign(cells, Carried{});
    for (const auto& m : sc_.materials) consts_.push_back(constants_of(m));

    for (const auto& f : sc_.fixes) {
        int i0, i1, j0, j1;
        detail::box_nodes(f.box, L_, mx_, my_, i0, i1, j0, j1);
        for (int j = j0; j <= j1; ++j)
            for (int i = i0; i <= i1; ++i) fixed_[node(i, j)] |= std::uint8_t(f.dirs);
    }
    for (std::size_t n = 0; n < nodes; ++n) if (fixed_[n]) fixed_nodes_.push_back(std::int32_t(n));
    fixed_rows_.assign(std::size_t(my_ + 2), 0);
    for (const std::int32_t n : fixed_nodes_) ++fixed_rows_[std::size_t(n / (mx_ + 1) + 1)];
    for (int j = 0; j <= my_; ++j) fixed_rows_[std::size_t(j + 1)] += fixed_rows_[std::size_t(j)];
    // Cell edges whose two nodes are both fixed across the edge: no point may cross them.
    fixed_edges_.assign(cells, 0);
    for (int j = 0; j < my_; ++j)
        for (int i = 0; i < mx_; ++i) {
            const int n1 = node(i, j), n2 = n1 + 1, n3 = n1 + mx_ + 1, n4 = n3 + 1;
            auto both = [&](int a, int b, int d) { return (fixed_[a] & d) && (fixed_[b] & d); };
            fixed_edges_[cell(i, j)] = std::uint8_t((both(n1, n2, kFixY) ? kEdgeBottom : 0) | (both(n3, n4, kFixY) ? kEdgeTop : 0) |
                                                    (both(n1, n3, kFixX) ? kEdgeLeft : 0) | (both(n2, n4, kFixX) ? kEdgeRight : 0));
        }
    for (const auto& w : sc_.walls) {
        WallState ws;
        int i0, i1, j0, j1;
        detail::wall_span(w.box, L_, mx_, my_, i0, i1, j0, j1);
        for (int j = j0; j <= j1; ++j)
            for (int i = i0; i <= i1; ++i) { ws.base_i.push_back(i); ws.base_j.push_back(j); }
        driven_nodes_.reserve(driven_nodes_.capacity() + 4 * ws.base_i.size());  // up to four lines each (impose_supports)
        // The cells a point may cross the wall's faces from in one step (mark_wall_cells).
        ws.face = {i0 * L_, j0 * L_, i1 * L_, j1 * L_};  // the box's nodes
        const std::size_t ci = std::size_t(i1 - i0 + 8), cj = std::size_t(j1 - j0 + 8);
        wall_cells_.reserve(wall_cells_.capacity() + ci * cj);
        ws.normal_x = w.smooth && i0 == i1;
        ws.normal_y = w.smooth && j0 == j1;
        walls_.push_back(std::move(ws));
    }
    mark_wall_cells();
    fix_rx_.assign(sc_.fixes.size(), 0.0);
    fix_ry_.assign(sc_.fixes.size(), 0.0);
    for (const std::int32_t n : fixed_nodes_) {  // each fixed direction's reaction goes to the first FIX card holding it
        const int i = n % (mx_ + 1), j = n / (mx_ + 1);
        std::int16_t ox = -1, oy = -1;
        for (std::size_t f = 0; f < sc_.fixes.size(); ++f) {
            int i0, i1, j0, j1;
            detail::box_nodes(sc_.fixes[f].box, L_, mx_, my_, i0, i1, j0, j1);
            if (i < i0 || i > i1 || j < j0 || j > j1) continue;
            if (ox < 0 && (sc_.fixes[f].dirs & kFixX)) ox = std::int16_t(f);
            if (oy < 0 && (sc_.fixes[f].dirs & kFixY)) oy = std::int16_t(f);
        }
        fix_owner_.push_back({ox, oy});
    }
    create_points();
    setup_water();
    if (sc_.geostatic) geostatic();
    if (modes_.mapping == Mapping::Smooth) {  // the step's scratch: the points never grow in number
        overlap_.assign(p_.size(), {});
        if (LPFDM_WIDE && kernel_ != Kernel::Reference) cell_rec_.assign(12 * std::size_t(mx_) * std::size_t(my_) + 4, 0.0);  // (smear_lanes)
        row_points_.assign(std::size_t(my_) + 1, 0);
    }
    if (modes_.advect == Advect::Flip) {
        flip_gx_.assign(p_.size(), 0.0); flip_gy_.assign(p_.size(), 0.0);
        flip_held_.reserve(fixed_nodes_.size() + driven_nodes_.capacity());  // (flip_transfer: no allocation in the step)
    }
    setup_dynamics();
    for (std::size_t w = 0; w < walls_.size(); ++w) contact_side(walls_[w], sc_.walls[w]);
    for (const Group& g : groups_) group_consts_.push_back(&consts_[std::size_t(g.mat_index)]);
    find_mohr_groups();
#if defined(_OPENMP)
    if (team_ > 1 && p_.size() > 4096) {  // the threaded point pass's room
        parts_.resize(std::size_t(team_));
        landings_.resize(std::size_t(team_));
        chunk_at_.assign(parts_.size() + 1, 0);
        p_.each_array([&](const char*, auto& v, Points::Use u, bool state) { if (!state && uses(sc_, u, true)) v.assign(p_.size(), {}); });
    }
    for (RowBlocks& b : row_blocks_) {  // the lattice phases' blocks of rows (by_rows)
        const std::size_t team = std::size_t(team_);
        b.at.assign(team + 1, 0.0); b.seconds.assign(team, 0.0); b.rows.assign(team + 1, 0);
    }
#endif
    row_ke_.assign(std::size_t(my_ + 1), 0.0);
    row_du_.assign(std::size_t(my_ + 1), 0.0);
    row_energy_.assign(std::size_t(my_ + 1), RowEnergy{});
    row_gained_.assign(std::size_t(my_ + 1), 0);
    map_to_lattice();
    strained_ = occupied_.grow(2, mx_, my_);
    live_nodes_ = {};
}

inline void Simulation::create_points() {
    // Groups: one per (material, ppc); masses quantised so that sums are exact.
    std::vector<std::pair<int, int>> keys;  // (material index, ppc)
    std::vector<double> count;
    std::vector<int> group_of(sc_.clusters.size(), -1);  // each cluster's group
    std::size_t npoints = 0;
    detail::made_points(sc_.clusters, L_, mx_, my_, [&](int, int, int k, int, int) {
        int& g = group_of[std::size_t(k)];
        if (g < 0) {
            const auto& c = sc_.clusters[std::size_t(k)];
            int mi = 0;
            while (sc_.materials[std::size_t(mi)].id != c.mat) ++mi;
            const std::pair<int, int> key{mi, c.ppc};
            auto it = std::find(keys.begin(), keys.end(), key);
            if (it == keys.end()) { keys.push_back(key); count.push_back(0); it = keys.end() - 1; }
            g = int(it - keys.begin());
        }
        count[std::size_t(g)] += 1;
        ++npoints;
    });
    double total = 0;
    for (std::size_t g = 0; g < keys.size(); ++g) {
        const double h = L_ / keys[g].second;
        total += count[g] * sc_.materials[std::size_t(keys[g].first)].rho * h * h;
    }
    int e = 0;
    std::frexp(total > 0 ? total : 1.0, &e);
    const int qexp = e - 52;  // quantum 2^(e-52): total < 2^53 quanta, so every sum is exact
    for (std::size_t g = 0; g < keys.size(); ++g) {
        const double h = L_ / keys[g].second;
        const double m = sc_.materials[std::size_t(keys[g].first)].rho * h * h;
        const double q = std::max(1.0, std::nearbyint(std::ldexp(m, -qexp)));
        const double mq = std::ldexp(q, qexp);
        groups_.push_back({keys[g].first, mq, mq / sc_.materials[std::size_t(keys[g].first)].rho, 0.5 * h});
    }

    const bool plastic = uses(sc_, Points::kPlastic, false), scatter = uses(sc_, Points::kScatter, false), flip = uses(sc_, Points::kFlip, false);
    const bool water = uses(sc_, Points::kWater, false), loaded = uses(sc_, Points::kLoad, false);
    p_.each_array([&](const char*, auto& v, Points::Use u, bool state) { if (state && uses(sc_, u, false)) v.reserve(npoints); });

    Random rng(sc_.seed);
    detail::made_points(sc_.clusters, L_, mx_, my_, [&](int i, int j, int k, int si, int sj) {
        const auto& c = sc_.clusters[std::size_t(k)];
        const std::uint16_t g = std::uint16_t(group_of[std::size_t(k)]);
        const int mi = keys[g].first;
        const Material& mat = sc_.materials[std::size_t(mi)];
        p_.x.push_back((i + (si + 0.5) / c.ppc) * L_);
        p_.y.push_back((j + (sj + 0.5) / c.ppc) * L_);
        for (auto* v : {&p_.sxx, &p_.syy, &p_.sxy, &p_.szz}) v->push_back(0.0);
        p_.vol.push_back(groups_[g].mass / mat.rho);
        p_.cell.push_back(cell(i, j));
        p_.id.push_back(std::int32_t(p_.id.size()));
        p_.group.push_back(g);
        if (plastic) { p_.plastic_shear.push_back(0.0); p_.yielded.push_back(0); p_.plastic_work.push_back(0.0); }
        if (flip) { p_.flip_ux.push_back(0.0); p_.flip_uy.push_back(0.0); }  // at rest
        if (water) { p_.pw.push_back(hydrostatic(mat, p_.x.back(), p_.y.back())); p_.wvol.push_back(p_.vol.back()); }
        if (loaded) { p_.load_x.push_back(0.0); p_.load_y.push_back(0.0); p_.load_axis.push_back(0); }
        if (!scatter) return;
        if (mat.scatter > 0) {
            const double cc = rng.truncated_normal(mat.c, mat.scatter * mat.c, 0, std::numeric_limits<double>::infinity(), false);
            const double ph = mat.phi_deg > 0 ? rng.truncated_normal(mat.phi_deg, mat.scatter * mat.phi_deg, 0, 90, true) : 0.0;
            p_.c0.push_back(cc);
            p_.n_phi.push_back(detail::flow_number(ph));
        } else {
            p_.c0.push_back(consts_[std::size_t(mi)].c);
            p_.n_phi.push_back(consts_[std::size_t(mi)].n_phi);
        }
        p_.sqrt_n_phi.push_back(std::sqrt(p_.n_phi.back()));
    });
    mass0_ = 0;
    for (std::size_t k = 0; k < p_.size(); ++k) mass0_ += groups_[p_.group[k]].mass;
    made_ = p_.size();
    x0_ = p_.x;  // (made in id order)
    y0_ = p_.y;
    for (const Track& t : sc_.tracks) {  // TRACK: the nearest point at step 0
        std::int32_t best = -1;
        double d2 = std::numeric_limits<double>::infinity();
        for (std::size_t k = 0; k < x0_.size(); ++k) {
            const double dx = x0_[k] - t.x, dy = y0_[k] - t.y, e = dx * dx + dy * dy;
            if (e < d2) { d2 = e; best = std::int32_t(k); }
        }
        tracked_.push_back(best);
    }
    if (sc_.reorder > 0) {  // reorder_points' room, so that the steps allocate nothing
        sorted_.reserve(made_);
        cell_count_.assign(std::size_t(mx_) * std::size_t(my_) + 1, 0);
        sort_buf_.resize(made_ * sizeof(double));
    }
}

LPFDM_DEF StrainIncrement Simulation::strain_of_cell(int i, int j) const { return cell_strain(dux_.data(), duy_.data(), node(i, j), mx_ + 1, 0.5 * invL_); }

LPFDM_DEF int Simulation::cell_holding(double x, double y) const {
    if (!(x >= 0 && x < mx_ * L_ && y >= 0 && y < my_ * L_)) return -1;
    return cell(std::min(mx_ - 1, int(x * invL_)), std::min(my_ - 1, int(y * invL_)));
}

inline void Simulation::add_to_cell(std::size_t c, double m, double v, double sxx, double syy, double sxy) {
    CellSums a = cell_sums(c);
    a.add(m, v, sxx, syy, sxy);
    store_sums(c, a);
}

LPFDM_DEF long Simulation::slot_of(std::int32_t id) const {
    for (std::size_t k = 0; k < p_.size(); ++k)
        if (p_.id[k] == id) return long(k);
    return -1;
}

LPFDM_DEF const std::vector<std::int32_t>& Simulation::by_id() const {
    slot_of_id_.assign(std::size_t(made_), -1);
    for (std::size_t k = 0; k < p_.size(); ++k) slot_of_id_[std::size_t(p_.id[k])] = std::int32_t(k);
    by_id_.clear();
    for (const std::int32_t k : slot_of_id_)
        if (k >= 0) by_id_.push_back(k);
    return by_id_;
}

LPFDM_DEF double Simulation::bytes_per_point() const {
    const double n = double(std::max<std::size_t>(1, p_.size()));
    double b = 0;
    p_.each_array([&](const char*, const auto& v, Points::Use, bool) { b += double(v.capacity() * sizeof(v[0])); });
    return b / n;
}

LPFDM_DEF long Simulation::first_nonfinite_point() const {
    for (std::size_t k = 0; k < p_.size(); ++k)
        if (!std::isfinite(p_.x[k] + p_.y[k] + p_.sxx[k] + p_.syy[k] + p_.sxy[k] + p_.szz[k] + p_.vol[k])) return long(k);
    return -1;
}

LPFDM_DEF void Simulation::worst_node(int& i, int& j, long& point) const {
    double worst = -1;
    i = j = 0;
    for (int b = 0; b <= my_; ++b)
        for (int a = 0; a <= mx_; ++a) {
            const int n = node(a, b);
            const double v = std::fabs(dux_[n]) + std::fabs(duy_[n]);
            const bool bad = !std::isfinite(v) || !std::isfinite(fx_[n]) || !std::isfinite(fy_[n]);
            if (bad || v > worst) { worst = bad ? std::numeric_limits<double>::infinity() : v; i = a; j = b; }
            if (bad) { b = my_ + 1; break; }
        }
    point = -1;
    for (std::size_t k = 0; k < p_.size() && point < 0; ++k) {
        const int c = p_.cell[k], ci = c % mx_, cj = c / mx_;
        if (ci >= i - 1 && ci <= i && cj >= j - 1 && cj <= j) point = long(k);
    }
}

// Points that left the lattice leave the cycle; their mass becomes outflow. The order
// of the remaining points is kept.
inline void Simulation::remove_departed() {
    const std::size_t n = p_.size();
    std::int32_t* cell = p_.cell.data();
    for (std::size_t k = 0; k < n; ++k) {
        if (cell[k] >= 0) continue;
        // A non-finite point also lands here; keep it so the guard can name it.
        if (std::isfinite(p_.x[k]) && std::isfinite(p_.y[k])) {
            mass_out_ += groups_[p_.group[k]].mass;
            es_.left_strain += strain_energy(k);  // the energy account keeps what it took along
            es_.left_potential += potential_energy(k);
            if (modes_.plastic) es_.left_plastic += p_.plastic_work[k];
        } else {
            cell[k] = 0;
        }
    }
    // Each array in turn, cell (which says who stays) last. Shrinking keeps capacity: no allocation.
    std::size_t w = 0;
    auto compact = [&](const char* name, auto& v, Points::Use, bool) {
        if (v.empty() || std::strcmp(name, "cell") == 0) return;
        w = 0;
        for (std::size_t k = 0; k < n; ++k)
            if (cell[k] >= 0) v[w++] = v[k];
        v.resize(w);
    };
    p_.each_array(compact);
    w = 0;
    for (std::size_t k = 0; k < n; ++k)
        if (cell[k] >= 0) cell[w++] = cell[k];
    p_.cell.resize(w);
    departed_ = 0;
}

// REORDER n: every n steps, at the end of the step, the points' storage is sorted by the
// cell they lie in, and by id within a cell (a counting sort by cell, then an insertion
// sort of each cell's few points by id). Points are made cell by cell; as they flow,
// neighbours in storage stop being neighbours on the lattice, and the fast point loop,
// which walks runs of points sharing a cell, loses its runs. Only the storage changes: the
// cycle is the same, but its sums over points (eq. 7, 8 into cells; the energy account)
// take their terms in storage order, so the results differ from an unsorted run in the
// last bits (the reference kernel sorts at the same steps, and gives the fast kernels'
// bits). Writers list the points by id (by_id), a state file keeps the storage order.
inline void Simulation::reorder_points() {
    const std::size_t n = p_.size();
    const std::int32_t* cell = p_.cell.data();
    const std::int32_t* id = p_.id.data();
    parts_known_ = false;  // advance_parted's chunks were ranges of the old order
    overlaps_known_ = false;  // and overlap_ is in the old order
    // Already in order, by cell and by id within each cell (no point has changed cell since
    // the last sort: a scene at rest, or one that has not yet moved): the new order would
    // be the old one, and nothing is moved (most sorts of a quiet scene).
    bool in_order = true;
    for (std::size_t k = 1; k < n && in_order; ++k) in_order = cell[k - 1] < cell[k] || (cell[k - 1] == cell[k] && id[k - 1] < id[k]);
    if (in_order) return;
    std::fill(cell_count_.begin(), cell_count_.end(), 0);
    for (std::size_t k = 0; k < n; ++k) ++cell_count_[std::size_t(cell[k]) + 1];
    for (std::size_t c = 1; c < cell_count_.size(); ++c) cell_count_[c] += cell_count_[c - 1];
    sorted_.resize(n);  // within the capacity reserved at set-up
    for (std::size_t k = 0; k < n; ++k) sorted_[std::size_t(cell_count_[std::size_t(cell[k])]++)] = std::int32_t(k);
    // Sorted by cell now; by id within each cell (the runs are short and mostly in order).
    for (std::size_t a = 1; a < n; ++a) {
        const std::int32_t k = sorted_[a];
        std::size_t b = a;
        while (b > 0 && cell[sorted_[b - 1]] == cell[k] && id[sorted_[b - 1]] > id[k]) {
            sorted_[b] = sorted_[b - 1];
            --b;
        }
        sorted_[b] = k;
    }
    // Every array of a point's state in the new order (the scratch arrays hold nothing
    // between steps), each thread moving its own range of it (the same bytes with any
    // team): this permutation is nearly 90 % of the sort's time, and what one thread does
    // alone is a larger share of a two-thread step.
    unsigned char* buf = sort_buf_.data();
    const std::int32_t* order = sorted_.data();
    [[maybe_unused]] const bool threads = !serial();
    p_.each_array([&](const char*, auto& v, Points::Use, bool state) {
        if (!state || v.empty()) return;
        using T = typename std::decay_t<decltype(v)>::value_type;
        T* a = v.data();
        LPFDM_OMP(omp parallel for schedule(static) num_threads(team_) if (threads))
        for (long k = 0; k < long(n); ++k) std::memcpy(buf + std::size_t(k) * sizeof(T), a + order[k], sizeof(T));
        LPFDM_OMP(omp parallel for schedule(static) num_threads(team_) if (threads))
        for (long k = 0; k < long(n); ++k) std::memcpy(a + k, buf + std::size_t(k) * sizeof(T), sizeof(T));
    });
}

// eq. 7 (cell mass) and eq. 8 (stress smeared over the cell, sum V sigma / L^2; kept
// here as sum V sigma and sum V; nodal_forces divides by max(L^2, sum V)).
inline void Simulation::clear_cells() {
    if (occupied_.empty()) return;
    // Rows by threads: at a million points this is some 10 MB a step.
    by_rows(kClearRows, occupied_.j0, occupied_.j1, occupied_.size(), [&](int j) { clear_row(j, 0, std::numeric_limits<int>::max()); });
}

// The sums of row j's cells in occupied_'s columns, of those numbered lo .. hi-1.
inline void Simulation::clear_row(int j, int lo, int hi) {
    const int c0 = std::max(cell(occupied_.i0, j), lo), c1 = std::min(j * mx_ + occupied_.i1, hi);
    if (c0 >= c1) return;
    for (auto* v : {&cmass_, &cvol_, &svxx_, &svyy_, &svxy_}) std::fill(v->data() + c0, v->data() + c1, 0.0);
    if (modes_.advect == Advect::Points) std::fill(carried_.data() + c0, carried_.data() + c1, Carried{});
    if (modes_.mapping == Mapping::Smooth)
        for (auto* v : {&shx_, &shy_, &smu_, &smv_}) std::fill(v->data() + c0, v->data() + c1, 0.0);
}

// eq. 7a/7b's nodes: the increments (ux, uy) of the four nodes of the cell whose node [1]
// is n1; and MOTION CENTRE's mean of them. Both kernels gather so (move_with_cell, the
// point loop's parts).
LPFDM_INLINE inline void Simulation::gather_nodes(int n1, double (&ux)[4], double (&uy)[4]) const {
    const int n2 = n1 + 1, n3 = n1 + mx_ + 1, n4 = n3 + 1;
    ux[0] = dux_[n1]; ux[1] = dux_[n2]; ux[2] = dux_[n3]; ux[3] = dux_[n4];
    uy[0] = duy_[n1]; uy[1] = duy_[n2]; uy[2] = duy_[n3]; uy[3] = duy_[n4];
}

LPFDM_INLINE inline void Simulation::gather_mean(int n1, double& umx, double& umy) const {
    double ux[4], uy[4];
    gather_nodes(n1, ux, uy);
    mean_of_four(ux[0], ux[1], ux[2], ux[3], umx); mean_of_four(uy[0], uy[1], uy[2], uy[3], umy);
}

// ======================================================================================
// BOUNDARIES: FIXED NODES AND WALLS
//
// Where the paper is open, the choices made here (each tested in tests/):
// * A cell edge whose two nodes are both fixed across it is impermeable: a point that
//   eq. 7a/7b would carry across it takes its move across the edge from the lattice's own
//   field in its cell instead, the bilinear interpolation of the four nodes' increments
//   (MOTION BILINEAR's), which the edge's fixed nodes hold at zero across it: a point at
//   height h above a fixed floor moves down by at most h times the share of the nodes
//   above, less than a cell in a stable step, so it cannot reach the floor. Its move along
//   the edge stays its cell's. The affine map moves a point on a fixed floor by
//   d_eps_yx dx when the nodes above move unequally; without a guard 14 % of a collapsing
//   column left through its rough floor. The guard was first a stop on the edge (the
//   move across clamped): the points beside the opening of trapdoor.deck were stopped
//   1 180 times in its last 2 000 steps, each put on the floor without the floor's nodes
//   resisting. The clamp stays as a last guard, counted (parked()); the moves the
//   lattice's field took over are counted by held(). (Taking the whole move from the
//   lattice's field, along the floor too, kept a lone point near a corner of its floor
//   cell from following the cell: the node above it, which it alone gave mass, fell on
//   for the whole run, 15 % of gravity's work left as kinetic energy.)
// * Moving walls: all nodes of a wall get (vx, vy) dt each step; after each whole cell
//   of travel along an axis the wall passes to the next line of nodes on that axis.
//   Constraints combine: a wall and a FIX (or two walls) may share nodes where they set
//   different directions, a SMOOTH wall's x beside a smooth base's FIX Y (validate refuses
//   a direction set by both at the start). Where a moving wall later meets a fixed node,
//   the fixed direction wins. While the wall's face lies
//   between two lines of nodes both are driven (the cell between moves with the wall): a
//   node behind the face left free, with the little mass of the points beside the face
//   and no material beyond it, let sand flow through a retaining wall moved away from
//   it. A row or column of nodes reaches along its length to the nodes of every cell
//   edge its segment covers (detail::wall_span), and no point crosses a wall's face
//   (Simulation::hold_by_walls, a guard: the nodes hold it). SMOOTH walls (a row or a
//   column of nodes) drive across their line only. A row or column of nodes with material on one side only (as the points were
//   made, WallState::side_x, side_y: those within a cell of it, or if none is that near,
//   all along it; far on both sides, the side it is driven towards; with none along it,
//   the inner side of the lattice's edge) is a contact: a node whose own increment
//   (eq. 13) would take it away from the wall into the material, or that has no mass, is
//   left free, so the wall pushes and never pulls (bonded both ways, a retaining wall
//   moved away from sand dragged it: 0.14-0.67 of Rankine's thrust; a wall made two cells
//   from a free block pulled it back as hard as it had pushed it, and carried it at its
//   own speed instead of letting it bounce off). A wall inside a cluster (material on
//   both sides, the paper's cap) or a box of nodes stays bonded. A row or column of
//   nodes inside a cluster drives the material line it started on instead,
//   interpolated between the two lines of nodes either side (Simulation::drive_embedded):
//   passed from line to line, the cap's cells between them unloaded at each pass and the
//   wall's force jumped by up to 59 %. The reported force is what the driven nodes exert
//   on the material, sum m (u - b) / dt^2 - F (b the increment eq. 13 began from).
// ======================================================================================

LPFDM_DEF void Simulation::set_wall_velocity(int wall_id, double vx, double vy) {
    for (auto& w : sc_.walls) if (w.id == wall_id) { w.vx = vx; w.vy = vy; }
}

inline double Simulation::edge_above(int k) const {
    double v = k * L_;
    while (int(v * invL_) < k) v = std::nextafter(v, std::numeric_limits<double>::infinity());
    return v;
}

inline double Simulation::edge_below(int k) const {
    double v = std::nextafter(k * L_, 0.0);
    while (int(v * invL_) >= k) v = std::nextafter(v, 0.0);
    return v;
}

// A cell edge fixed across is impermeable: a point of cell c that moved from (x0, y0) to
// (x, y) across it takes its move across the edge from the lattice's bilinear field
// instead (held()); were it still across, it stops on the edge, inside its cell
// (parked()); nor does any point cross a wall's face.
inline void Simulation::stop_at_edges(int c, double x0, double y0, double& x, double& y) const {
    stop_at_edges(c % mx_, c / mx_, fixed_edges_[std::size_t(c)], x0, y0, x, y);
}
// ... of cell (ci, cj) with fixed edges fe (fixed_edges_).
LPFDM_INLINE inline void Simulation::stop_at_edges(int ci, int cj, std::uint8_t fe, double x0, double y0, double& x, double& y) const {
    const double xi = ci * L_, yj = cj * L_;
    auto below = [&] { return (fe & kEdgeBottom) && y < yj; };
    auto above = [&] { return (fe & kEdgeTop) && y >= (cj + 1) * L_; };
    auto left = [&] { return (fe & kEdgeLeft) && x < xi; };
    auto right = [&] { return (fe & kEdgeRight) && x >= (ci + 1) * L_; };
    const bool across_x = left() || right(), across_y = below() || above();
    if (across_x || across_y) {  // across the edge, the lattice's own motion, which its fixed nodes hold
        double ux[4], uy[4], xb, yb, dx, dy;
        gather_nodes(node(ci, cj), ux, uy);
        move_point_bilinear(x0, y0, xi, yj, invL_, ux, uy, xb, yb, dx, dy);
        if (across_x) x = xb;
        if (across_y) y = yb;
        holding_.add();
    }
    bool stopped = false;  // the last guard
    if (below()) { y = edge_above(cj); stopped = true; }
    if (above()) { y = edge_below(cj + 1); stopped = true; }
    if (left()) { x = edge_above(ci); stopped = true; }
    if (right()) { x = edge_below(ci + 1); stopped = true; }
    if (fe & kEdgeWall) stopped |= hold_by_walls(x0, y0, x, y);
    if (stopped) parking_.add();  // (parked())
}

// Fixed directions, then moving walls (paper section 3), imposed on the increments eq. 13
// made; the reactions are what the supports exert on the material (minus the net nodal
// force they cancel). Returns the nodes the walls drove. integrate() relies on this, in a
// scene that neither shakes nor absorbs: the increments change only at fixed nodes (to
// zero, in their fixed directions) and inside the range returned; a support that changed
// others would leave its rows' energy terms stale there.
// The work a support does in one direction of node n, holding it at c where eq. 13 began
// from b: its force S = m (c - b) / dt^2 - F on the step's mean increment (b + c) / 2
// (into w), and S c / 2 (into h: energy() takes the last step's off, trapezoidal sums).
inline void Simulation::support_work(std::size_t n, double b, double c, double f, double& w, double& h) const {
    const double m = inertia()[n];
    if (m == 0) return;
    const double S = m * (c - b) / (sc_.dt_s * sc_.dt_s) - f;
    w += 0.5 * S * (b + c);
    h += 0.5 * S * c;
}

inline Range Simulation::impose_supports() {
    rx_ = ry_ = 0;
    double hf = 0;
    std::fill(fix_rx_.begin(), fix_rx_.end(), 0.0);
    std::fill(fix_ry_.begin(), fix_ry_.end(), 0.0);
    // SHAKE (rigid): the nodes fixed in a shaken direction move with the ground (those
    // with mass: a node without it touches no material), and the reaction is the force
    // that moves them, m (c - b) / dt^2 - F; their work is the ground's.
    const bool shake_x = shaken_dirs() & kFixX, shake_y = shaken_dirs() & kFixY;
    const double dt2 = sc_.dt_s * sc_.dt_s;
    double hg = 0;
    auto shaken = [&](std::size_t u, double& du, double b, double f, double g, double& r, double& rf) {
        const double m = inertia()[u];
        du = m > 0 ? g : 0.0;
        const double S = m > 0 ? m * (du - b) / dt2 - f : -f;
        r += S; rf += S;
        support_work(u, b, du, f, es_.w_ground, hg);
    };
    for (std::size_t a = 0; a < fixed_nodes_.size(); ++a) {
        const std::size_t u = std::size_t(fixed_nodes_[a]);
        if ((fixed_[u] & kFixX) && shake_x) shaken(u, dux_[u], dux_old_[u], fx_[u], ground_[0].du, rx_, fix_rx_[std::size_t(fix_owner_[a].x)]);
        else if (fixed_[u] & kFixX) {
            dux_[u] = 0; rx_ -= fx_[u]; fix_rx_[std::size_t(fix_owner_[a].x)] -= fx_[u];
            support_work(u, dux_old_[u], 0.0, fx_[u], es_.w_fixes, hf);
        }
        if ((fixed_[u] & kFixY) && shake_y) shaken(u, duy_[u], duy_old_[u], fy_[u], ground_[1].du, ry_, fix_ry_[std::size_t(fix_owner_[a].y)]);
        else if (fixed_[u] & kFixY) {
            duy_[u] = 0; ry_ -= fy_[u]; fix_ry_[std::size_t(fix_owner_[a].y)] -= fy_[u];
            support_work(u, duy_old_[u], 0.0, fy_[u], es_.w_fixes, hf);
        }
    }
    es_.h_fixes = hf;
    es_.h_ground = hg;
    const bool flip = modes_.advect == Advect::Flip;
    const std::vector<double>& mass = inertia();
    for (const std::int32_t n : driven_nodes_) driven_[std::size_t(n)] = 0;
    driven_nodes_.clear();  // capacity reserved at set-up: no allocation
    Range wall_nodes{};
    double hw = 0;
    for (std::size_t w = 0; w < walls_.size(); ++w) {
        WallState& ws = walls_[w];
        const Wall& spec = sc_.walls[w];
        ws.fx = ws.fy = 0;
        const double ddx = ws.normal_y ? 0.0 : spec.vx * sc_.dt_s, ddy = ws.normal_x ? 0.0 : spec.vy * sc_.dt_s;
        // While the wall's face lies between two lines of nodes (it has passed the line it
        // drives, ws.shift, and not yet reached the next), a node of the next line with no
        // material beyond it (a wall moving away from the material: the node is behind the
        // face) is driven too: the cell between moves with the wall. Left free, such a node
        // has only the little mass of the points beside the face and nothing beyond it, and
        // sand flowed through a retaining wall moved away from it. A node with material
        // beyond it (a wall pushing into the material) stays free: that material is ahead.
        auto lead = [&](double travel, double d, int shift) {
            const double past = (travel + d) * invL_ - shift;  // cells beyond the driven line after this increment
            return d > 0 && past > 1e-9 ? 1 : d < 0 && past < -1e-9 ? -1 : 0;
        };
        const int li = lead(ws.dx, ddx, ws.shift_i), lj = lead(ws.dy, ddy, ws.shift_j);
        if (ws.embedded) drive_embedded(ws, ddx, ddy, hw, wall_nodes);
        for (std::size_t q = 0; q < ws.base_i.size() && !ws.embedded; ++q)
            for (int b = 0; b <= std::abs(lj); ++b)
                for (int a = 0; a <= std::abs(li); ++a) {
                    const int i = ws.base_i[q] + ws.shift_i + a * li, j = ws.base_j[q] + ws.shift_j + b * lj;
                    if (i < 0 || j < 0 || i > mx_ || j > my_) continue;
                    if ((a && !empty_beyond(i, j, li, 0)) || (b && !empty_beyond(i, j, 0, lj))) continue;
                    const int n = node(i, j);
                    const std::size_t u = std::size_t(n);
                    const bool new_node = !driven_[u];
                    // A wall with material on one side pushes and never pulls: a node whose own
                    // increment (eq. 13) takes it away from the wall into the material, or that has
                    // no material to move, is left free.
                    if (new_node && (ws.side_x || ws.side_y)) {
                        const double away = ws.side_x ? (dux_[u] - ddx) * ws.side_x : (duy_[u] - ddy) * ws.side_y;
                        if (away > 0 || mass[u] == 0) continue;
                    }
                    if (!(fixed_[u] & kFixX) && !(driven_[u] & kFixX) && !ws.normal_y) {  // a smooth row of nodes is driven in y only
                        ws.fx += flip ? mass[u] * (ddx - dux_old_[u]) / dt2 - fx_[u] : -fx_[u];  // with FLIP the impact too (flip_transfer)
                        dux_[u] = ddx;
                        support_work(u, dux_old_[u], dux_[u], fx_[u], es_.w_walls, hw);
                        driven_[u] |= kFixX;
                    }
                    if (!(fixed_[u] & kFixY) && !(driven_[u] & kFixY) && !ws.normal_x) {  // and a smooth column in x only
                        ws.fy += flip ? mass[u] * (ddy - duy_old_[u]) / dt2 - fy_[u] : -fy_[u];
                        duy_[u] = ddy;
                        support_work(u, duy_old_[u], duy_[u], fy_[u], es_.w_walls, hw);
                        driven_[u] |= kFixY;
                    }
                    if (new_node && driven_[u]) driven_nodes_.push_back(n);
                    wall_nodes = wall_nodes.unite({i, i + 1, j, j + 1});
                }
        // Travel after this increment; whole cells travelled move the wall to the next line.
        // (A smooth wall travels across its line only.)
        ws.dx0 = ws.dx; ws.dy0 = ws.dy;
        ws.dx += ddx;
        ws.dy += ddy;
        ws.shift_i = int(std::trunc(ws.dx * invL_ * (1 + 1e-12)));
        ws.shift_j = int(std::trunc(ws.dy * invL_ * (1 + 1e-12)));
    }
    es_.h_walls = hw;
    mark_wall_cells();
    return wall_nodes;
}

// The cells holding the points that may cross a wall's face in the next point pass: those
// within a cell of the wall's faces (hold_by_walls) anywhere between its travel before and after the
// increment just imposed (a point moves less than half a cell a step).
inline void Simulation::mark_wall_cells() {
    for (const std::int32_t c : wall_cells_) fixed_edges_[std::size_t(c)] &= std::uint8_t(~kEdgeWall);
    wall_cells_.clear();  // capacity reserved at set-up: no allocation
    for (std::size_t w = 0; w < walls_.size(); ++w) {
        const WallState& ws = walls_[w];
        const Box& b = ws.face;
        const double xa = b.x0 + std::min(ws.dx0, ws.dx) - 2 * L_, xb = b.x1 + std::max(ws.dx0, ws.dx) + 2 * L_;
        const double ya = b.y0 + std::min(ws.dy0, ws.dy) - 2 * L_, yb = b.y1 + std::max(ws.dy0, ws.dy) + 2 * L_;
        const int i0 = std::max(0, int(std::floor(xa * invL_))), i1 = std::min(mx_ - 1, int(std::floor(xb * invL_)));
        const int j0 = std::max(0, int(std::floor(ya * invL_))), j1 = std::min(my_ - 1, int(std::floor(yb * invL_)));
        for (int j = j0; j <= j1; ++j)
            for (int i = i0; i <= i1; ++i) {
                std::uint8_t& f = fixed_edges_[std::size_t(cell(i, j))];
                if (f & kEdgeWall) continue;
                f |= kEdgeWall;
                wall_cells_.push_back(cell(i, j));
            }
    }
}

// A wall's faces are impermeable: a point that was on one side of a face before the step
// (the face at the wall's travel dx0, dy0) and would end on it or beyond it (the face at
// dx, dy) stops a millionth of a cell short of it, on its own side. The faces are the
// edges of the box of the nodes the wall drives (detail::wall_span; one segment for a
// line of nodes), moved with its travel. The nodes hold the face: the lattice beside it
// cannot carry a point across, and a stop here is a last guard, counted (parked()). (The
// faces once reached a cell beyond the end nodes, to hold the row beside a base the wall
// stopped a node short of; the free node there let the lattice carry the material into
// the face, and the points stopped on it packed the cell.)
inline bool Simulation::hold_by_walls(double x0, double y0, double& x, double& y) const {
    const double gap = 1e-6 * L_;
    const double x_in = x, y_in = y;
    for (std::size_t w = 0; w < walls_.size(); ++w) {
        const WallState& ws = walls_[w];
        const Box& b = walls_[w].face;
        // Faces across y (at y0 and y1 of the box; none for a column of nodes), spanning the
        // box's x range now.
        if (b.x1 > b.x0 && x >= b.x0 + ws.dx && x <= b.x1 + ws.dx)
            for (const double yf : {b.y0, b.y1}) {
                const double before = y0 - (yf + ws.dy0), after = y - (yf + ws.dy);
                if (before < 0 && after >= 0) y = yf + ws.dy - gap;
                else if (before > 0 && after <= 0) y = yf + ws.dy + gap;
                if (b.y1 == b.y0) break;
            }
        // Faces across x (at x0 and x1; none for a row of nodes), spanning the box's y range now.
        if (b.y1 > b.y0 && y >= b.y0 + ws.dy && y <= b.y1 + ws.dy)
            for (const double xf : {b.x0, b.x1}) {
                const double before = x0 - (xf + ws.dx0), after = x - (xf + ws.dx);
                if (before < 0 && after >= 0) x = xf + ws.dx - gap;
                else if (before > 0 && after <= 0) x = xf + ws.dx + gap;
                if (b.x1 == b.x0) break;
            }
    }
    return x != x_in || y != y_in;  // (a point at NaN is stopped by nothing here)
}

// The side of a wall's line of nodes its material lies on (WallState::side_x, side_y), from
// the points as made, along the line's length: those within a cell of the line; if none
// lies that near, all of them (a wall that meets the material later: bonded, it pulled a
// free block it had pushed, and stuck to it); with material on both sides only farther
// than a cell, the side the wall is driven towards (bonded if it is not driven across
// its line); with none along it, the inner side of the lattice's edge it lies on (bonded
// inside the lattice). Material on both sides within a cell: the wall is embedded (the
// paper's cap).
inline void Simulation::contact_side(WallState& ws, const Wall& spec) const {
    const Box& b = ws.face;
    const bool column = b.x0 == b.x1 && b.y1 > b.y0, row = b.y0 == b.y1 && b.x1 > b.x0;
    if (!column && !row) return;  // a box of nodes: bonded
    long before = 0, after = 0, far_before = 0, far_after = 0;
    for (std::size_t k = 0; k < p_.size(); ++k) {
        const double along = column ? p_.y[k] : p_.x[k], lo = column ? b.y0 : b.x0, hi = column ? b.y1 : b.x1;
        const double across = (column ? p_.x[k] : p_.y[k]) - (column ? b.x0 : b.y0);
        if (along < lo || along > hi) continue;
        const bool near = std::fabs(across) < L_;
        (near ? before : far_before) += across < 0;
        (near ? after : far_after) += across > 0;
    }
    ws.embedded = before && after;
    if (!before && !after) { before = far_before; after = far_after; }  // nothing near: the material farther along it
    int side = before && !after ? -1 : after && !before ? 1 : 0;
    if (before && after && !ws.embedded) {  // far on both sides: the side it is driven towards
        const double v = column ? spec.vx : spec.vy;
        side = v > 0 ? 1 : v < 0 ? -1 : 0;
    }
    const double at = column ? b.x0 : b.y0, edge = (column ? mx_ : my_) * L_;
    if (!before && !after) side = at <= 0 ? 1 : at >= edge ? -1 : 0;  // no material along it: the lattice's edge
    (column ? ws.side_x : ws.side_y) = side;
}

// A wall inside the material drives the material line it started on, wherever that line
// now lies between two lines of nodes: the increment interpolated there (linearly, as the
// points move) is the wall's, (1 - f) u_a + f u_b = d for the nodes a, b either side, f
// the fraction of a cell from a. The pair keeps one free motion, r = u_b - u_a (u_a = d -
// f r, u_b = d + (1 - f) r), advanced by eq. 13-14 with its own mass and force, m_a f^2 +
// m_b (1 - f)^2 and (1 - f) F_b - f F_a. So the line of nodes the wall drives changes
// continuously as it travels: driven one line at a time, the cap's cell row between two
// lines, compressed while below the wall, was suddenly above it after each cell of
// travel, and the wall's force jumped by up to 59 %. The force on the material is the
// supports' sum m (u - b) / dt^2 - F (b: the increment eq. 13 began from). The wall's
// travel along its line still passes whole cells (shift_i, shift_j).
inline void Simulation::drive_embedded(WallState& ws, double ddx, double ddy, double& hw, Range& wall_nodes) {
    const Box& bx = ws.face;
    const bool column = bx.x0 == bx.x1;  // else a row
    const double dt2 = sc_.dt_s * sc_.dt_s;
    const std::vector<double>& mass = inertia();
    // The material line now, in cells across the lattice, and the lines of nodes either side.
    const double at = (column ? bx.x0 + ws.dx : bx.y0 + ws.dy) * invL_;
    const int lo = int(std::floor(at + 1e-9)), across_max = column ? mx_ : my_;
    const double f = at - lo < 1e-9 ? 0.0 : at - lo;
    for (std::size_t q = 0; q < ws.base_i.size(); ++q) {
        const int along = column ? ws.base_j[q] + ws.shift_j : ws.base_i[q] + ws.shift_i;
        if (along < 0 || along > (column ? my_ : mx_) || lo < 0 || lo > across_max) continue;
        const int hi = f > 0 && lo < across_max ? lo + 1 : lo;
        const std::size_t a = std::size_t(column ? node(lo, along) : node(along, lo)), b = std::size_t(column ? node(hi, along) : node(along, hi));
        for (const std::uint8_t dir : {kFixX, kFixY}) {
            if ((dir == kFixX && ws.normal_y) || (dir == kFixY && ws.normal_x)) continue;  // a smooth wall: across its line only
            std::vector<double>& du = dir == kFixX ? dux_ : duy_;
            const std::vector<double>& b0 = dir == kFixX ? dux_old_ : duy_old_;
            const std::vector<double>& mean_along = dir == kFixX ? mean_ux_ : mean_uy_;  // DAMPING WINDOW (empty without it)
            const std::vector<double>& F = dir == kFixX ? fx_ : fy_;
            const double d = dir == kFixX ? ddx : ddy;
            auto held = [&](std::size_t u) { return (fixed_[u] & dir) || (driven_[u] & dir); };
            auto drive = [&](std::size_t u, double value) {
                du[u] = value;
                (dir == kFixX ? ws.fx : ws.fy) += mass[u] * (value - b0[u]) / dt2 - F[u];
                support_work(u, b0[u], value, F[u], es_.w_walls, hw);
                if (!driven_[u]) driven_nodes_.push_back(std::int32_t(u));
                driven_[u] |= dir;
            };
            // A node without mass moves with the wall (nothing to push; the nodes' output
            // shows the wall), and the other node of the pair then carries the line alone.
            const bool free_a = !held(a), free_b = hi != lo && !held(b);
            if (free_a && mass[a] == 0) drive(a, d);
            if (free_b && mass[b] == 0) drive(b, d);
            if (!free_b || mass[b] == 0) {  // on a line of nodes, or the other side held or empty: that line
                if (free_a && mass[a] > 0) drive(a, d);
            } else if (!free_a || mass[a] == 0) {
                drive(b, d);
            } else {
                const double wa = 1 - f, wb = f;
                // The pair's inertia: its masses by the line's weights. ADVECT FLIP's are the
                // transfer's (inertia()); where the pair holds only slivers of squares past a
                // face (a wall reaching out of the material), those are of order s^2 in the
                // sliver's width s while eq. 8's forces are of order s, and the pair's mode
                // ran away (test_hard.cpp: 0.3 m at step 4). Below 1 % of eq. 10's masses
                // of the pair (a square inside a cell gives each of its nodes 1 / PPC^2 of
                // eq. 10's share or more: 1 % or more up to PPC=10; above, a lone square in
                // a cell's far corner may also switch, which only gives the pair the paper's
                // inertia) the mode takes eq. 10's, whose ratio to the force is the paper's
                // cycle's. (Without FLIP the two are the same masses.)
                const double mf = mass[a] * wb * wb + mass[b] * wa * wa, m10 = nmass_[a] * wb * wb + nmass_[b] * wa * wa;
                const double m = mf < 0.01 * m10 ? m10 : mf, force = wa * F[b] - wb * F[a];
                double r = 0;
                damped_increment(b0[b] - b0[a], force, m, dt2, sc_.damping, r, mean_at(mean_along, b) - mean_at(mean_along, a));  // eq. 13-14 for the pair's free motion
                drive(a, d - wb * r);
                drive(b, d + wa * r);
            }
        }
        wall_nodes = wall_nodes.unite(column ? Range{lo, hi + 1, along, along + 1} : Range{along, along + 1, lo, hi + 1});
    }
}

// Whether the cells beyond node (i, j) in direction (di, dj) (one of them 0) hold no mass.
inline bool Simulation::empty_beyond(int i, int j, int di, int dj) const {
    auto empty = [&](int a, int b) { return a < 0 || b < 0 || a >= mx_ || b >= my_ || cmass_[std::size_t(cell(a, b))] == 0; };
    if (di) { const int a = di > 0 ? i : i - 1; return empty(a, j - 1) && empty(a, j); }
    const int b = dj > 0 ? j : j - 1;
    return empty(i - 1, b) && empty(i, b);
}

// The increments eq. 13 starts from, at the nodes it will visit (the energy account).
inline void Simulation::keep_increments(const Range& nodes) {
    if (nodes.empty()) return;
    for (int j = nodes.j0; j < nodes.j1; ++j) {
        const std::size_t a = std::size_t(node(nodes.i0, j)), b = std::size_t(node(nodes.i1 - 1, j)) + 1;
        std::copy(dux_.begin() + long(a), dux_.begin() + long(b), dux_old_.begin() + long(a));
        std::copy(duy_.begin() + long(a), duy_.begin() + long(b), duy_old_.begin() + long(a));
    }
}

// ======================================================================================
// THE ENERGY ACCOUNT
//
// Where the paper is open, the choices made here (each tested in tests/):
// * The energy account (Simulation::energy) uses the leapfrog's own kinetic energy
//   (m du_old . du_new / 2 dt^2) and trapezoidal nodal works, so an undamped linear step
//   conserves it exactly; strain energy and plastic work are the points' (V from eq. 8).
// ======================================================================================

inline double Simulation::strain_energy(std::size_t k) const {
    const Stress s{p_.sxx[k], p_.syy[k], p_.sxy[k], p_.szz[k]};
    const double e = 0.5 * energy_volume(k) * compliance_product(*group_consts_[p_.group[k]], s, s);
    if (!modes_.water) return e;
    const double kwn = group_water_[p_.group[k]].kwn;  // WATER: the pore water's, V p^2 n / (2 Kw)
    return kwn > 0 ? e + 0.5 * energy_volume(k) * p_.pw[k] * p_.pw[k] / kwn : e;
}

inline double Simulation::energy_volume(std::size_t k, double vol) const {
    const double v0 = groups_[p_.group[k]].vol0;
    return modes_.advect == Advect::Flip ? v0 : std::min(vol, v0);
}

// The energy account of one step, after the supports were imposed: per row of nodes
// (energy_row_terms) the leapfrog's kinetic energy (b . c), gravity's work and the
// dissipation of the damping eq. 13 applied (free directions only), each as force x the
// mean increment (b + c) / 2 and force x c / 2 (energy() takes the latter off: trapezoidal
// sums); then the rows in order.

// Row j's terms, nodes i0 .. i1-1: each sum kept in four parts, node i's terms going to
// part i % 4, the parts added at the end; four nodes at a time in the lanes of a vector
// when Wide (the lanes are the parts), one at a time otherwise: the same bits either way.
// A node without mass adds exact zeros, so every kernel gets the same sums whatever
// columns it visits.
template <class Wide> inline void Simulation::energy_row_terms(int j, int i0, int i1, Wide) {
    const double *nm = nmass_.data(), *bxs = dux_old_.data(), *bys = duy_old_.data(), *cxs = dux_.data(), *cys = duy_.data();
    const double *fxs = fx_.data(), *fys = fy_.data();
    const double *mxs = mean_ux_.empty() ? nullptr : mean_ux_.data(), *mys = mean_uy_.empty() ? nullptr : mean_uy_.data();  // DAMPING WINDOW
    const bool damped = sc_.damping > 0;
    const int row = node(0, j);
    double part[7][4] = {};  // kin sbx sby scx scy wd hd, by i % 4
    auto one_node = [&](int i) {
        const int n = row + i, l = i & 3;
        const double m = nm[n], bx = bxs[n], by = bys[n], cx = cxs[n], cy = cys[n];
        part[0][l] += m * (bx * cx + by * cy);
        part[1][l] += m * (bx + cx); part[2][l] += m * (by + cy);
        part[3][l] += m * cx; part[4][l] += m * cy;
        if (damped) {  // eq. 14's force |F| sgn(b - mean), every direction (tally_energy takes the held ones off)
            const double rx = bx - (mxs ? mxs[n] : 0.0), ry = by - (mys ? mys[n] : 0.0);
            const double dx = std::fabs(fxs[n]) * double((rx > 0) - (rx < 0)), dy = std::fabs(fys[n]) * double((ry > 0) - (ry < 0));
            part[5][l] += dx * (bx + cx) + dy * (by + cy);
            part[6][l] += dx * cx + dy * cy;
        }
    };
    int i = i0;
#if LPFDM_WIDE
    if constexpr (Wide::value) {
        using detail::v4d;
        for (; i < i1 && (i & 3); ++i) one_node(i);
        v4d acc[7];
        for (int k = 0; k < 7; ++k) acc[k] = v4d{part[k][0], part[k][1], part[k][2], part[k][3]};
        const v4d one = {1, 1, 1, 1}, zero{};
        for (; i + 4 <= i1; i += 4) {
            const int n = row + i;
            v4d m, bx, by, cx, cy;
            detail::load(nm + n, m); detail::load(bxs + n, bx); detail::load(bys + n, by); detail::load(cxs + n, cx); detail::load(cys + n, cy);
            acc[0] += m * (bx * cx + by * cy);
            acc[1] += m * (bx + cx); acc[2] += m * (by + cy);
            acc[3] += m * cx; acc[4] += m * cy;
            if (damped) {
                v4d fx, fy, ax, ay, rx = bx, ry = by;
                detail::load(fxs + n, fx); detail::load(fys + n, fy);
                detail::abs_of(fx, ax); detail::abs_of(fy, ay);
                if (mxs) {
                    v4d ox, oy;
                    detail::load(mxs + n, ox); detail::load(mys + n, oy);
                    rx = bx - ox; ry = by - oy;
                }
                const v4d sx = (rx > zero ? one : zero) - (rx < zero ? one : zero), sy = (ry > zero ? one : zero) - (ry < zero ? one : zero);
                const v4d dx = ax * sx, dy = ay * sy;
                acc[5] += dx * (bx + cx) + dy * (by + cy);
                acc[6] += dx * cx + dy * cy;
            }
        }
        for (int k = 0; k < 7; ++k)
            for (int l = 0; l < 4; ++l) part[k][l] = acc[k][l];
    }
#endif
    for (; i < i1; ++i) one_node(i);
    double sum[7];
    for (int k = 0; k < 7; ++k) sum[k] = ((part[k][0] + part[k][1]) + part[k][2]) + part[k][3];
    row_energy_[std::size_t(j)] = RowEnergy{sum[0], sum[1], sum[2], sum[3], sum[4], sum[5], sum[6]};
}

// The rows j0 .. j1-1 of energy_row_terms, in order, into the running sums.
inline void Simulation::tally_energy(int j0, int j1) {
    const double dt2 = sc_.dt_s * sc_.dt_s, gx = sc_.gravity_x, gy = sc_.gravity_y, alpha = sc_.damping;
    RowEnergy t;
    for (int j = j0; j < j1; ++j) {
        const RowEnergy& r = row_energy_[std::size_t(j)];
        t.kin += r.kin; t.sbx += r.sbx; t.sby += r.sby; t.scx += r.scx; t.scy += r.scy; t.wd += r.wd; t.hd += r.hd;
    }
    // The rows counted damping on every direction; the fixed and driven ones had none.
    auto held_off = [&](std::size_t n, unsigned dirs) {
        if (alpha == 0 || nmass_[n] == 0) return;
        const double bx = dux_old_[n], by = duy_old_[n], cx = dux_[n], cy = duy_[n];
        const double rx = bx - mean_at(mean_ux_, n), ry = by - mean_at(mean_uy_, n);  // DAMPING WINDOW: about the mean
        const double dx = (dirs & kFixX) ? std::fabs(fx_[n]) * double((rx > 0) - (rx < 0)) : 0.0;
        const double dy = (dirs & kFixY) ? std::fabs(fy_[n]) * double((ry > 0) - (ry < 0)) : 0.0;
        t.wd -= dx * (bx + cx) + dy * (by + cy);
        t.hd -= dx * cx + dy * cy;
    };
    for (const std::int32_t n : fixed_nodes_) held_off(std::size_t(n), fixed_[std::size_t(n)]);
    for (const std::int32_t n : driven_nodes_) held_off(std::size_t(n), driven_[std::size_t(n)] & ~fixed_[std::size_t(n)]);
    es_.kinetic = 0.5 * t.kin / dt2;
    es_.peak_kinetic = std::max(es_.peak_kinetic, es_.kinetic);
    es_.w_gravity += 0.5 * (gx * t.sbx + gy * t.sby); es_.h_gravity = 0.5 * (gx * t.scx + gy * t.scy);
    es_.d_damping += 0.5 * alpha * t.wd; es_.h_damping = 0.5 * alpha * t.hd;
}

// The strain and potential energy of the points before the first step (they may have
// been given an initial stress after the Simulation was made).
inline void Simulation::start_energy() {
    double e = 0, v = 0;
    for (std::size_t k = 0; k < p_.size(); ++k) { e += strain_energy(k); v += potential_energy(k); }
    es_.strain0 = e;
    es_.potential0 = v;
}

LPFDM_DEF double Simulation::packing() const {
    double most = 0;
    for (const double v : cvol_) most = std::max(most, v);
    return most / (L_ * L_);
}

// ======================================================================================
// SHIFT (not in the paper): points that crowd move apart
//
// The choices made here (each tested in tests/):
// * The cycle can carry points together faster than their cells' strain compresses them:
//   a flow drawn out into thin lines leaves cells of many points beside empty ones, each
//   point keeping its volume, and nothing in eq. 1-14 moves them apart; eq. 8 then gives
//   such a cell several times the mass and stress its area can hold. SHIFT [RATE=r]
//   [ABOVE=a] moves them apart every kShiftEvery = 10 steps, after the step, as particle
//   shifting does in SPH:
//   - the fill: each point stands for a square of side sqrt(V) (at most L) about it; f at
//     each node of the lattice of spacing h = L/2 is the squares' area in the L x L window
//     about that node (the four sub-cells around it that lie in the lattice) over the
//     window's area, 1 where the points tile the material as made, at any PPC;
//   - each point moves down the gradient of the excess e = max(f - a, 0), bilinear in its
//     sub-cell: delta = -r h (h grad e), at most L/10; where f <= a nothing moves;
//   - a point stays where it is if the move would take it out of the lattice, across a
//     fixed cell edge (of the cells about the edge or corner it crosses) or into a cell
//     near a wall's face (kEdgeWall), or if it lies in such a cell or carries a LOAD: the
//     supports' guards are not crossed;
//   - only after a step whose largest eq. 8 sum exceeds a L^2 (packing()): a scene that
//     never crowds so (nor, counted whole, past the guard's limit below) runs bit for bit
//     as it does without the card;
//   - and after every step a guard (shift_relief): where the points lying in a cell (V at
//     most V0 each, as eq. 8 counts them) hold more than twice its area (kShiftLimit, or
//     a if larger), the cell gives points, one a round and at most 8, to the edge
//     neighbours that stay within it with them: the point nearest such an edge, put just
//     across it (L / 1000). Under MAPPING SMOOTH it counts whole points too, which eq. 8
//     there does not (a cell may hold nine points' centres and packing() read 1), so
//     there it may move points where the pass's gate would not. Why a guard besides the
//     pass: the pass's fill, smooth over L, cannot see it: flows leave lines of points about
//     0.9 L apart, two of which fall in one cell beside cells holding one (the fill
//     reads 0.9 there, eq. 8's sum 2.25), and eq. 12's cell-wise motion brings them so
//     between passes; the guard moves the nearest line's points a few hundredths of L;
//   - every 10 steps, not every step: the pass costs about as much as the paper's step
//     (bench_flow.deck: 8.5 s without, 10.8 s every 10 steps, one thread, tests/README.md;
//     every step at r / 10 for the same packing took twice as long as every 10 steps);
//   - a point keeps its mass, volume, stress and (ADVECT FLIP) its own increment, so mass,
//     and under FLIP momentum, are kept exactly; the potential energy the moves change is
//     the account's w_shift, work in. Under eq. 12 the nodes keep their increments while
//     masses move under them, as they do when eq. 7a/7b moves the points.
//   Why squares on the half-spacing lattice: the fill of whole cells (eq. 8's sums, or their
//   means at the nodes) cannot see cells that alternate full and empty, the pattern flows
//   leave, and moving points down it made bench_flow.deck's packing worse (4.5 -> 9.7);
//   points counted whole in the sub-cells (no squares) held it to 3.5-4.0 only, creating
//   6-14 % of the energy in play. tests/README.md gives what SHIFT changes on the flows.
// ======================================================================================

// After a step (every kernel the same code, the points in point order).
inline void Simulation::shift_points() {
    if (!sc_.shift) return;
    const double above = sc_.shift_above, limit = std::max(kShiftLimit, above);
    if ((step_ + 1) % kShiftEvery == 0 && packing() > above) shift_pass();
    shift_relief(limit);
}

// After every step: a cell whose points' volumes (whole points, by the cell they lie in)
// sum above limit L^2 gives points to its edge neighbours, in rounds of one point a cell
// (at most kShiftRounds), the cells in index order: the point nearest one of its cell's
// edges whose neighbour across it stays within the limit with it (of two as near, the
// lower id), moved just across that edge; rounds go on while a cell is over the limit and
// the last round moved a point. The choices do not depend on the points' storage order
// (REORDER) or on the step's number (a state read into a used Simulation). The pass's
// guards (shift_may_move, shift_may_cross), and the lattice's edges.
inline bool Simulation::shift_relief(double limit) {
    // (under the paper's mapping eq. 8's sums are these sums, made where the points are now)
    if (modes_.mapping == Mapping::Paper && packing() <= limit) return false;
    const double cap = limit * L_ * L_, margin = 1e-3 * L_, inf = std::numeric_limits<double>::infinity();
    auto vol = [&](std::size_t k) { return std::min(p_.vol[k], groups_[p_.group[k]].vol0); };  // as eq. 8 counts it
    ShiftCell* sc = shift_cells_.data();
    const long stamp = ++shift_stamp_;  // (a call's own: entries of earlier calls, or runs, read as empty)
    auto sum = [&](int c) { return sc[c].stamp == stamp ? sc[c].sum : 0.0; };
    int* full = shift_full_.data();  // the cells over the limit
    int nfull = 0;
    for (std::size_t k = 0; k < p_.size(); ++k) {
        const int c = p_.cell[k];
        if (c < 0 || !std::isfinite(p_.x[k] + p_.y[k])) continue;
        if (sc[c].stamp != stamp) sc[c] = ShiftCell{0.0, inf, stamp, -1, -1, false};
        if ((sc[c].sum += vol(k)) > cap && !sc[c].listed) { sc[c].listed = true; full[nfull++] = c; }
    }
    if (!nfull) return false;
    std::sort(full, full + nfull);  // in cell order, and each cell's choice by distance, then id: not the storage's order
    double work = 0;
    long moved = 0;
    Range box;  // the cells moves left and entered
    for (int round = 0, left = nfull, now = 1; left && now && round < kShiftRounds; ++round) {
        for (std::size_t k = 0; k < p_.size(); ++k) {  // each full cell's best move
            const int c = p_.cell[k];
            if (c < 0 || sum(c) <= cap || !shift_may_move(k)) continue;
            const int i = c % mx_, j = c / mx_;
            const double u = p_.x[k] - i * L_, v = p_.y[k] - j * L_;
            const double d[4] = {u, L_ - u, v, L_ - v};  // to the left, right, bottom, top edge
            for (int e = 0; e < 4; ++e) {
                const bool nearer = d[e] < sc[c].best || (d[e] == sc[c].best && sc[c].point >= 0 && p_.id[k] < p_.id[std::size_t(sc[c].point)]);
                if (!nearer) continue;
                const int ni = i + (e == 0 ? -1 : e == 1 ? 1 : 0), nj = j + (e == 2 ? -1 : e == 3 ? 1 : 0);
                if (ni < 0 || nj < 0 || ni >= mx_ || nj >= my_) continue;
                const int cn = nj * mx_ + ni;
                if (!shift_may_cross(c, cn) || sum(cn) + vol(std::size_t(k)) > cap) continue;
                sc[c].best = d[e]; sc[c].point = std::int32_t(k); sc[c].edge = std::int8_t(e);
            }
        }
        left = now = 0;
        for (int f = 0; f < nfull; ++f) {  // the moves, in cell order
            const int c = full[f];
            const std::int32_t k = sc[c].point;
            if (k < 0) { left += sum(c) > cap; continue; }  // (none has room now; it may after others' moves)
            const int e = sc[c].edge, i = c % mx_, j = c / mx_;
            const int cn = c + (e == 0 ? -1 : e == 1 ? 1 : e == 2 ? -mx_ : mx_);
            sc[c].best = inf; sc[c].point = -1; sc[c].edge = -1;
            if (sum(cn) + vol(std::size_t(k)) > cap) { ++left; continue; }  // (filled by another cell's move this round)
            const double before = potential_energy(std::size_t(k));
            if (e == 0) p_.x[k] = i * L_ - margin;
            else if (e == 1) p_.x[k] = (i + 1) * L_ + margin;
            else if (e == 2) p_.y[k] = j * L_ - margin;
            else p_.y[k] = (j + 1) * L_ + margin;
            p_.cell[k] = cn;
            work += potential_energy(std::size_t(k)) - before;
            ++moved;
            ++now;
            if (sc[cn].stamp != stamp) sc[cn] = ShiftCell{0.0, inf, stamp, -1, -1, false};
            sc[c].sum -= vol(std::size_t(k)); sc[cn].sum += vol(std::size_t(k));
            if (sc[c].sum > cap) ++left;
            box = box.unite(Range{std::min(i, cn % mx_), std::max(i, cn % mx_) + 1, std::min(j, cn / mx_), std::max(j, cn / mx_) + 1});
        }
    }
    return shift_moved(work, moved, box);
}

// The supports' guards, which neither the pass nor the guard crosses: a point may move if
// it lies on the lattice, finite, without a LOAD, and not in a cell near a wall's face
// (kEdgeWall, where hold_by_walls keeps the face); from cell c into its edge or corner
// neighbour cn if no edge of the two cells about the edge or corner it crosses is fixed
// and cn is not near a wall's face.
inline bool Simulation::shift_may_move(std::size_t k) const {
    const int c = p_.cell[k];
    return c >= 0 && std::isfinite(p_.x[k] + p_.y[k]) && !(modes_.loads && p_.load_axis[k]) && !(fixed_edges_[std::size_t(c)] & kEdgeWall);
}

inline bool Simulation::shift_may_cross(int c, int cn) const {
    const int di = cn % mx_ - c % mx_, dj = cn / mx_ - c / mx_;
    const std::uint8_t from = std::uint8_t((di > 0 ? kEdgeRight : di < 0 ? kEdgeLeft : 0) | (dj > 0 ? kEdgeTop : dj < 0 ? kEdgeBottom : 0));
    const std::uint8_t into = std::uint8_t((di > 0 ? kEdgeLeft : di < 0 ? kEdgeRight : 0) | (dj > 0 ? kEdgeBottom : dj < 0 ? kEdgeTop : 0));
    return !(fixed_edges_[std::size_t(c)] & from) && !(fixed_edges_[std::size_t(cn)] & (into | kEdgeWall));
}

// After a pass or the guard: the account (w_shift, the moves), and where points moved
// the last mapping, which the next step reads (eq. 5's cells with mass, MAPPING SMOOTH's
// centroids, packing()), made anew where the points are now (with it, a restart's state),
// its sums cleared first in every cell the step's mapping wrote and the moves entered
// (`box`; the reference cycle keeps no occupied_ of its own).
inline bool Simulation::shift_moved(double work, long moved, const Range& box) {
    es_.w_shift += work;
    shifted_ += moved;
    if (!moved) return false;
    occupied_ = occupied_.unite(box);
    map_points();
    return true;
}

// The pass, every kShiftEvery steps (the choices at the head of this section).
inline bool Simulation::shift_pass() {
    const double above = sc_.shift_above;
    const int sx = 2 * mx_, sy = 2 * my_, n1 = sx + 1;
    const double h = 0.5 * L_, ih = 1 / h;
    Range cells;  // the box of the points' cells
    for (std::size_t k = 0; k < p_.size(); ++k) {
        const int c = p_.cell[k];
        if (c >= 0 && std::isfinite(p_.x[k] + p_.y[k])) cells = cells.unite(Range{c % mx_, c % mx_ + 1, c / mx_, c / mx_ + 1});
    }
    const Range box = cells.grow(1, mx_, my_);  // holds every point's square
    const int I0 = 2 * box.i0, I1 = 2 * box.i1, J0 = 2 * box.j0, J1 = 2 * box.j1;  // sub-cells I0 .. I1-1, sub-nodes I0 .. I1
    double* fill = shift_fill_.data();
    double* ex = shift_excess_.data();
    // The lengths of [c0, c1] (a square's side along one axis) in the sub-cells from its
    // first, in units of h, and that first sub-cell (at most 3: the side is at most 2h). A
    // point lies in the lattice, so c0 > -h and the sub-cells before the lattice's get 0.
    auto parts = [&](double c0, double c1, int m, double (&o)[3]) {
        const double u0 = c0 * ih, u1 = c1 * ih;
        const int i0 = int(std::floor(u0)), i1 = std::min(int(std::floor(u1)), m - 1);
        o[0] = o[1] = o[2] = 0;
        for (int i = i0; i <= std::min(i1, i0 + 2); ++i) o[i - i0] = i >= 0 ? std::min(u1, i + 1.0) - std::max(u0, double(i)) : 0.0;  // (a side of 2h exactly may round to four)
        return i0;
    };
    for (std::size_t k = 0; k < p_.size(); ++k) {  // the squares' areas in the sub-cells, over h^2
        const double a = 0.5 * std::min(std::sqrt(std::max(p_.vol[k], 0.0)), L_);
        if (p_.cell[k] < 0 || !(a > 0) || !std::isfinite(p_.x[k] + p_.y[k])) continue;  // (not finite: the health check stops the run)
        double ox[3], oy[3];
        const int i0 = parts(p_.x[k] - a, p_.x[k] + a, sx, ox), j0 = parts(p_.y[k] - a, p_.y[k] + a, sy, oy);
        for (int j = 0; j < 3; ++j) {
            if (oy[j] == 0) continue;
            double* row = fill + std::size_t(j0 + j) * std::size_t(sx);
            for (int i = 0; i < 3; ++i)
                if (ox[i] != 0) row[i0 + i] += ox[i] * oy[j];
        }
    }
    for (int J = J0; J <= J1; ++J) {  // the excess at the sub-nodes: the mean of the sub-cells around, less a
        const bool bottom = J == 0, top = J == sy;
        const double* below = fill + std::size_t(std::max(J - 1, 0)) * std::size_t(sx);
        const double* upper = fill + std::size_t(std::min(J, sy - 1)) * std::size_t(sx);
        double* e = ex + std::size_t(J) * std::size_t(n1);
        for (int I = I0; I <= I1; ++I) {
            const int a0 = std::max(I - 1, 0), a1 = std::min(I, sx - 1);
            const double s = (bottom ? 0.0 : below[a0] + (a1 != a0 ? below[a1] : 0.0)) + (top ? 0.0 : upper[a0] + (a1 != a0 ? upper[a1] : 0.0));
            const int n = (a1 != a0 ? 2 : 1) * (bottom || top ? 1 : 2);
            e[I] = std::max(s / n - above, 0.0);
        }
    }
    const double cap = 0.1 * L_, rate = sc_.shift_rate;
    double work = 0;
    long moved = 0;
    for (std::size_t k = 0; k < p_.size(); ++k) {
        if (!shift_may_move(k)) continue;
        const int c = p_.cell[k];
        const double x = p_.x[k], y = p_.y[k];
        const int I = std::clamp(int(x * ih), 0, sx - 1), J = std::clamp(int(y * ih), 0, sy - 1);
        const double u = x * ih - I, v = y * ih - J;
        const double* e = ex + std::size_t(J) * std::size_t(n1) + std::size_t(I);
        const double e00 = e[0], e10 = e[1], e01 = e[n1], e11 = e[n1 + 1];
        if (e00 == 0 && e10 == 0 && e01 == 0 && e11 == 0) continue;
        const double gx = (1 - v) * (e10 - e00) + v * (e11 - e01), gy = (1 - u) * (e01 - e00) + u * (e11 - e10);  // h grad e
        double dx = -rate * h * gx, dy = -rate * h * gy;
        const double len2 = dx * dx + dy * dy;
        if (!(len2 > 0)) continue;
        if (len2 > cap * cap) { const double r = cap / std::sqrt(len2); dx *= r; dy *= r; }
        const double xn = x + dx, yn = y + dy;
        const int cn = cell_holding(xn, yn);
        if (cn < 0 || (cn != c && !shift_may_cross(c, cn))) continue;
        const double before = potential_energy(k);
        p_.x[k] = xn; p_.y[k] = yn; p_.cell[k] = cn;
        work += potential_energy(k) - before;
        ++moved;
    }
    for (int J = J0; J < J1; ++J) std::fill(fill + std::size_t(J) * std::size_t(sx) + std::size_t(I0), fill + std::size_t(J) * std::size_t(sx) + std::size_t(I1), 0.0);
    for (int J = J0; J <= J1; ++J) std::fill(ex + std::size_t(J) * std::size_t(n1) + std::size_t(I0), ex + std::size_t(J) * std::size_t(n1) + std::size_t(I1) + 1, 0.0);
    return shift_moved(work, moved, box);
}

LPFDM_DEF double Simulation::excess_pressure() const {
    if (!modes_.water) return 0;
    double most = -std::numeric_limits<double>::infinity();
    for (std::size_t k = 0; k < p_.size(); ++k) {
        if (group_water_[p_.group[k]].kwn == 0) continue;
        most = std::max(most, p_.pw[k] - hydrostatic(sc_.materials[std::size_t(groups_[p_.group[k]].mat_index)], p_.x[k], p_.y[k]));
    }
    return std::isfinite(most) ? most : 0.0;
}

LPFDM_DEF Simulation::Energy Simulation::energy() const {
    double strain = 0, potential = 0, plastic = 0;
    for (std::size_t k = 0; k < p_.size(); ++k) {
        strain += strain_energy(k);
        potential += potential_energy(k);
        if (modes_.plastic) plastic += p_.plastic_work[k];
    }
    Energy e;
    e.kinetic = es_.kinetic;
    e.strain = strain + es_.left_strain - es_.strain0;
    e.gravity = potential + es_.left_potential - es_.potential0;
    e.w_walls = es_.w_walls - es_.h_walls;
    e.w_fixes = es_.w_fixes - es_.h_fixes;
    e.w_gravity = es_.w_gravity - es_.h_gravity;
    e.d_damping = es_.d_damping - es_.h_damping;
    e.d_plastic = plastic + es_.left_plastic;
    e.w_ground = es_.w_ground - es_.h_ground - es_.h_input;
    e.d_absorb = es_.d_absorb - es_.h_absorb;
    e.w_fixes += es_.w_held - es_.h_held;  // the reactions an absorbing edge took over at START
    e.w_loads = w_loads_ - h_loads_;
    e.d_water = d_water_;
    e.d_slip = es_.d_slip;
    e.w_shift = es_.w_shift;
    const double in = e.w_walls + e.w_fixes + e.w_ground + e.w_loads + e.w_shift;
    const double out = e.d_damping + e.d_plastic + e.d_absorb + e.d_water + e.d_slip;
    // (at least 1e-10 of the energies whose differences the terms are: below that the
    // account's own rounding, as a scene exactly at rest has, would read as energy made)
    const double rounding = 1e-10 * (std::fabs(es_.strain0) + std::fabs(es_.potential0));
    const double scale = std::max({std::fabs(in), e.kinetic + std::fabs(e.strain) + std::fabs(e.gravity), es_.peak_kinetic, std::fabs(out), rounding});
    e.error = scale > 0 ? (in - e.kinetic - e.strain - e.gravity - out) / scale : 0.0;
    return e;
}

// The largest unbalanced force (free directions: neither fixed nor driven by a wall) over
// the mean gross force of the nodes with mass and a free direction, after the last step. Taken when asked, from the forces and masses the step
// left (integrate() changes neither): two square roots per node that a step without a
// history row does not pay. Rows are summed in row order, as a step would.
LPFDM_DEF double Simulation::unbalanced_ratio() const {
    const Range nr = integrated_;
    const double g = std::hypot(sc_.gravity_x, sc_.gravity_y), gx = sc_.gravity_x, gy = sc_.gravity_y;
    double fmax = 0, fgross = 0;
    long counted = 0;
    for (int j = nr.j0; j < nr.j1; ++j) {
        double row_gross = 0;
        for (int i = nr.i0; i < nr.i1; ++i) {
            const int n = node(i, j);
            const double m = nmass_[std::size_t(n)];
            const std::uint8_t fix = fixed_[std::size_t(n)] | driven_[std::size_t(n)];  // fixed or driven by a wall
            if (m == 0 || fix == (kFixX | kFixY)) continue;
            const double fx = fx_[std::size_t(n)], fy = fy_[std::size_t(n)];
            const double fxf = (fix & kFixX) ? 0.0 : fx, fyf = (fix & kFixY) ? 0.0 : fy;
            fmax = std::max(fmax, std::sqrt(fxf * fxf + fyf * fyf));
            const double sx = fx - gx * m, sy = fy - gy * m;
            row_gross += std::sqrt(sx * sx + sy * sy) + m * g;
            ++counted;
        }
        fgross += row_gross;
    }
    return counted && fgross > 0 ? fmax / (fgross / counted) : 0.0;
}

// ======================================================================================
// PORE WATER AND LOADS (WATER, DRAIN, LOAD)
//
// A saturated point (its material has POROSITY n > 0) carries its pore pressure p
// (compression positive) beside its stress. The stress it carries, and its model sees, is
// the effective stress; the lattice feels the total stress sigma' - p I (tension
// positive): eq. 8's sums take -V p on their diagonal. Each step, after the points' phase
// and before the nodal forces, both kernels call water_pass:
// 1. Undrained: dp = -(Kw / n) d_eps_vol, d_eps_vol = V / V_before - 1, the point's own
//    volume change (eq. 6's d_eps_xx + d_eps_yy, to rounding).
// 2. Darcy flow between cells (not UNDRAINED), explicit, on the cells as FLAC's is on its
//    zones. A cell's water points pool their water: its potential Phi = sum s (p - rho_w
//    g . x) / C over its water points, s = V n / Kw, C = sum s its storage (every point
//    in it then takes Phi back, p = Phi + rho_w g . x: the cell is the flow's resolution,
//    and water at rest in it stays hydrostatic), its conductivity k = sum V k / sum V.
//    Across an edge between two such cells the volume
//    (k_ab / gamma_w)(Phi_a - Phi_b) dt flows (k_ab their harmonic mean); across a drained
//    edge (DRAIN) (2 k_a / gamma_w)(Phi_a - Phi_drain) dt leaves, from half a cell away,
//    Phi_drain the hydrostatic pore pressure's potential at the edge. A free surface (an
//    edge to a cell inside the lattice holding no point) is a seepage face: water under pressure
//    leaves there to p = 0 at the face, as to a drain, and none enters; below a
//    RESERVOIR's level it is drained to the reservoir both ways. The lattice's edges and
//    edges to dry material are impermeable unless drained. A cell whose water is at or below zero pressure (sum V n p / Kw <= 0:
//    above the water table, or sucked by dilation) takes no part and its points keep their
//    pressure: the flow is saturated flow only (above the table lpfdm models no
//    unsaturated flow; pooled with the rest, such cells drained down into the table). A cell's net inflow dW makes its potential Phi + dW / C: the water's
//    volume sum V n p / Kw changes by the drains' flow only, to rounding.
//    Alone, the flow's update is stable while dt lambda <= 2 for the largest eigenvalue
//    lambda of C^-1 T; coupled with the lattice it is not: a pressure mode that the update
//    overshoots (1 - dt lambda < 0) drives the skeleton, whose volume change drives it
//    back (a column 20 cells high grew without bound at 0.58 of the first bound; a model
//    of one mode, u'' = -a u - p, p taking c du then the factor 1 - f, is unstable for
//    every f > 1 whatever a and c). So dt lambda <= 1, which dt sum_edges T / C <= 1/2 in
//    every cell assures (Gershgorin): the deck's dt is refused above the limit of a full
//    cell with four open edges, n L^2 gamma_w / (8 Kw k), or with DRAIN cards of one that
//    also has a drained edge (2 k more), n L^2 gamma_w / (12 Kw k) (validate); an edge's
//    T is capped at min(C_a, C_b) / (8 dt), which binds only in cells holding less than a
//    full cell and in cells with more drained edges, keeping them stable and the exchange
//    conservative (such a cell drains more slowly than Darcy's law says).
//    gamma_w = rho_w |g| (rho_w 9.81 without gravity).
// 3. The total stress: -V p (V and the cells' shares as eq. 8 took the point's stress,
//    with every mapping and transfer) added to the cell's sums of sigma_xx, sigma_yy.
// The mechanical step sees the water's stiffness, Kw / n added to K (stable_dt).
// LOAD: each node of a LOAD line takes the traction times its share of the line's length;
// the material point nearest the node at step 0 carries that force, and gives it each
// step to the four nodes of its cell by the bilinear weights of its position: the load
// follows the material's surface as it moves. Its work is booked like a wall's.
// The energy account counts the water's stored energy V n p^2 / (2 Kw) with the strain
// energy, and what the flow and the drains took out of it as d_water.
// ======================================================================================

inline double Simulation::hydrostatic(const Material& m, double, double y) const {
    const Water& w = sc_.water;
    if (!w.on || m.porosity <= 0 || !(w.table > -std::numeric_limits<double>::infinity())) return 0;
    return std::max(0.0, -w.rhow * sc_.gravity_y * (w.table - y));
}

inline void Simulation::setup_water() {
    if (modes_.water) {
        const double g = std::hypot(sc_.gravity_x, sc_.gravity_y);
        gamma_w_ = sc_.water.rhow * (g > 0 ? g : 9.81);
        for (const Group& gr : groups_) {
            const Material& m = sc_.materials[std::size_t(gr.mat_index)];
            GroupWater w;
            if (m.porosity > 0) { w.n = m.porosity; w.kwn = sc_.water.kw / m.porosity; w.mobility = m.perm / gamma_w_; }
            w.vol0 = gr.vol0;
            group_water_.push_back(w);
        }
        const std::size_t cells = std::size_t(mx_) * std::size_t(my_);
        for (auto* v : {&wv_, &wp_, &wk_, &wc_, &wnew_, &wq_, &wr_, &wkc_, &wphi_, &wqx_, &wqy_}) v->assign(cells, 0.0);
        wde_.assign(p_.size(), 0.0);  // (the points never grow in number)
        water_rows_.assign(std::size_t(my_) + 1, 0);
        water_cell_points_.assign(cells, 0);
        drain_edges_.assign(cells, 0);
        std::vector<std::uint8_t> drained(std::size_t(mx_ + 1) * std::size_t(my_ + 1), 0);
        for (const Drain& d : sc_.drains) {
            int i0, i1, j0, j1;
            detail::box_nodes(d.box, L_, mx_, my_, i0, i1, j0, j1);
            for (int j = j0; j <= j1; ++j)
                for (int i = i0; i <= i1; ++i) drained[std::size_t(node(i, j))] = 1;
        }
        for (int j = 0; j < my_; ++j)
            for (int i = 0; i < mx_; ++i) {
                const std::size_t n1 = std::size_t(node(i, j)), n2 = n1 + 1, n3 = n1 + std::size_t(mx_) + 1, n4 = n3 + 1;
                drain_edges_[std::size_t(cell(i, j))] = std::uint8_t((drained[n1] && drained[n2] ? kEdgeBottom : 0) | (drained[n3] && drained[n4] ? kEdgeTop : 0) |
                                                                     (drained[n1] && drained[n3] ? kEdgeLeft : 0) | (drained[n2] && drained[n4] ? kEdgeRight : 0));
            }
    }
    if (modes_.loads) {
        const std::size_t nodes = std::size_t(mx_ + 1) * std::size_t(my_ + 1);
        load_fx_.assign(nodes, 0.0); load_fy_.assign(nodes, 0.0); load_mark_.assign(nodes, 0);
        for (const Load& ld : sc_.loads) {
            int i0, i1, j0, j1;
            detail::box_nodes(ld.box, L_, mx_, my_, i0, i1, j0, j1);
            for (int j = j0; j <= j1; ++j)
                for (int i = i0; i <= i1; ++i) {
                    // the node's share of the line: half of each line segment beside it
                    const double share = 0.5 * L_ * ((i > i0) + (i < i1) + (j > j0) + (j < j1));
                    const double nx = i * L_, ny = j * L_;
                    double d2 = std::numeric_limits<double>::infinity();
                    for (std::size_t k = 0; k < p_.size(); ++k) {
                        const double dx = p_.x[k] - nx, dy = p_.y[k] - ny;
                        d2 = std::min(d2, dx * dx + dy * dy);
                    }
                    // the nearest points share it (two or four equally near on a regular layout)
                    const double tie = d2 + 1e-9 * L_ * L_;
                    int near = 0;
                    for (std::size_t k = 0; k < p_.size(); ++k) {
                        const double dx = p_.x[k] - nx, dy = p_.y[k] - ny;
                        near += dx * dx + dy * dy <= tie;
                    }
                    for (std::size_t k = 0; k < p_.size(); ++k) {
                        const double dx = p_.x[k] - nx, dy = p_.y[k] - ny;
                        if (dx * dx + dy * dy > tie) continue;
                        p_.load_x[k] += ld.tx * share / near;
                        p_.load_y[k] += ld.ty * share / near;
                        p_.load_axis[k] = j0 == j1 ? 1 : 2;
                    }
                }
        }
        std::size_t loaded = 0;
        for (std::size_t k = 0; k < p_.load_x.size(); ++k) loaded += p_.load_x[k] != 0 || p_.load_y[k] != 0;
        load_nodes_.reserve(sc_.reservoir.on ? nodes : 4 * loaded);  // RESERVOIR: any node may take its pressure
    }
}

// GEOSTATIC: each point's effective vertical stress is the weight above its centre in its
// column of cells, per unit width: sigma'_yy = -(|g| / L) (sum of the masses of the
// points above it + half those level with it), each mass times (rho - rho_w) / rho where
// the point starts below the water table (buoyant), and sigma'_xx = sigma'_zz = K0
// sigma'_yy (K0 = nu / (1 - nu) of the point's material unless the card gives it), no
// shear. Exact for level ground; under a slope a state near equilibrium that local
// damping settles. Water above the material (a RESERVOIR) adds to p and to the total
// stress alike: nothing to sigma'.
inline void Simulation::geostatic() {
    const double g = -sc_.gravity_y, eps = 1e-9 * L_;
    std::vector<std::vector<std::size_t>> cols(static_cast<std::size_t>(mx_));
    for (std::size_t k = 0; k < p_.size(); ++k) cols[std::size_t(p_.cell[k] % mx_)].push_back(k);
    for (auto& col : cols) {
        std::sort(col.begin(), col.end(), [&](std::size_t a, std::size_t b) { return p_.y[a] > p_.y[b] || (p_.y[a] == p_.y[b] && a < b); });
        auto weight = [&](std::size_t k) {
            const Material& m = sc_.materials[std::size_t(groups_[p_.group[k]].mat_index)];
            const bool wet = modes_.water && m.porosity > 0 && p_.y[k] < sc_.water.table;
            return groups_[p_.group[k]].mass * (wet ? (m.rho - sc_.water.rhow) / m.rho : 1.0);
        };
        double above = 0;
        for (std::size_t a = 0; a < col.size();) {
            std::size_t b = a;
            double level = 0;  // the points level with col[a]
            while (b < col.size() && p_.y[col[a]] - p_.y[col[b]] <= eps) level += weight(col[b++]);
            const double syy = -g / L_ * (above + 0.5 * level);
            for (std::size_t q = a; q < b; ++q) {
                const std::size_t k = col[q];
                const Material& m = sc_.materials[std::size_t(groups_[p_.group[k]].mat_index)];
                const double k0 = sc_.k0 >= 0 ? sc_.k0 : m.nu / (1 - m.nu);
                p_.syy[k] = syy;
                p_.sxx[k] = p_.szz[k] = k0 * syy;
                p_.sxy[k] = 0;
            }
            above += level;
            a = b;
        }
    }
}

namespace detail {
// water_pass's first pass over the points of cells c0 .. c1-1 (low: and those outside the
// lattice), in point order: 1, each point's undrained response p to its volume change since
// its pressure last took one (V against V_before), and 2, its terms into its cell's sums
// (not UNDRAINED): sum V, sum s (p - rho_w g . x), sum V k / gamma_w, sum s, sum s p, with
// s = V n / Kw its storage.
// While the points stay in one cell, its sums stay in registers (t*), stored when a point
// of another cell comes: the same additions in the same order as adding each term into
// the arrays, where a chain of additions through memory waits for each store.
inline void water_sums(const WaterPoints w, int c0, int c1, bool low, double* sv, double* sp, double* sk, double* sc, double* sq) {
    std::ptrdiff_t at = -1;  // the cell whose sums are in t*
    double tv = 0, tp = 0, tk = 0, tc = 0, tq = 0;
    auto store = [&]() LPFDM_INLINE {
        if (at >= 0) { sv[at] = tv; sp[at] = tp; sk[at] = tk; sc[at] = tc; sq[at] = tq; }
    };
    auto mine = [&](std::size_t k) LPFDM_INLINE {
        const int c = w.cell[k];
        return (c < 0 ? low : c >= c0 && c < c1) && w.gw[w.group[k]].kwn != 0;
    };
    auto take = [&](std::size_t k, double v, double p, double s, double sphi, double vk, double spk) LPFDM_INLINE {
        w.pw[k] = p;
        w.wvol[k] = v;
        const std::ptrdiff_t c = w.cell[k];
        if (c < 0 || !w.flow) return;
        if (c != at) {
            store();
            at = c;
            tv = sv[c]; tp = sp[c]; tk = sk[c]; tc = sc[c]; tq = sq[c];
        }
        tv += v;
        tp += sphi;  // the point's potential
        tk += vk;
        tc += s;
        tq += spk;
    };
    for (std::size_t k = 0; k < w.n; ++k) {
        if (!mine(k)) continue;
        const GroupWater& g = w.gw[w.group[k]];
        const double v = w.vol[k];
        const double p = w.pw[k] - g.kwn * (v / w.wvol[k] - 1);  // 1. the undrained response
        const double s = v / g.kwn;
        take(k, v, p, s, s * (p - w.rw * (w.gx * w.x[k] + w.gy * w.y[k])), v * g.mobility, s * p);
    }
    store();
}

// water_pass's second pass over the points of cells c0 .. c1-1, in point order: 2, the
// pressure p1 = Phi + rho_w g . x its cell's water now gives each point whose cell's water
// flows (sc: its storage, 0 where it takes no part; phi: its potential Phi after the
// exchange), and the stored energy that took, V (p1^2 - p^2) / (2 Kw / n), subtracted
// from dw (one: one thread) or kept in de; with the
// paper's mapping, 3: -V p into the cell's sums of sigma_xx and sigma_yy, with the volume
// the point's stress took (energy_volume: V0 with ADVECT FLIP, else min(V, V0)), the
// cell's sums in registers as water_sums keeps them. Returns dw.
inline double water_pressures(const WaterPoints w, int c0, int c1, const double* sc, const double* phi, double* sxx, double* syy, double* de, bool one, double dw) {
    std::ptrdiff_t at = -1;
    double txx = 0, tyy = 0;
    auto store = [&]() LPFDM_INLINE {
        if (at >= 0) { sxx[at] = txx; syy[at] = tyy; }
    };
    auto mine = [&](std::size_t k) LPFDM_INLINE {
        const int c = w.cell[k];
        return c >= c0 && c < c1 && w.gw[w.group[k]].kwn != 0;
    };
    auto flows = [&](std::size_t k) LPFDM_INLINE { return w.flow && sc[w.cell[k]] != 0; };
    auto take = [&](std::size_t k, double v, double p, double e) LPFDM_INLINE {
        w.pw[k] = p;
        if (one) dw -= e;
        else de[k] = e;
        if (w.smooth) return;
        const std::ptrdiff_t c = w.cell[k];
        if (c != at) {
            store();
            at = c;
            txx = sxx[c]; tyy = syy[c];
        }
        txx -= v * p;
        tyy -= v * p;
    };
    auto volume = [&](double vol, double v0) LPFDM_INLINE { return w.flip ? v0 : std::min(vol, v0); };
    for (std::size_t k = 0; k < w.n; ++k) {
        if (!mine(k)) continue;
        const GroupWater& g = w.gw[w.group[k]];
        const double v = volume(w.vol[k], g.vol0);
        double e = 0, p = w.pw[k];
        if (flows(k)) {
            const double p1 = phi[w.cell[k]] + w.rw * (w.gx * w.x[k] + w.gy * w.y[k]);
            e = 0.5 * v * (p1 * p1 - p * p) / g.kwn;
            p = p1;
        }
        take(k, v, p, e);
    }
    store();
    return dw;
}
}  // namespace detail

// 1, 2 and 3 for every point. Each point's own updates go by threads in any order; every
// sum takes its terms in the order one pass in point order (or cell order) gives them, so
// that one thread and many give the same bits: the cells' sums (2, and 3's total stress)
// by bands of rows of cells, each band taking every point whose cell is in its rows, in
// point order (by_rows, water_rows_); the stored energy each point's new pressure takes,
// kept per point and summed in point order (detail::water_sums, water_pressures). No
// AVX2 version: four points' arithmetic in the lanes of a vector, their terms then added
// one point after another, made the run 0.8 times as fast (tools/README.md): the passes
// wait on their sums, not on their arithmetic.
inline void Simulation::water_pass() {
    if (!modes_.water) return;
    const bool flow = !sc_.water.undrained, smooth = modes_.mapping == Mapping::Smooth, flip = modes_.advect == Advect::Flip;
    const double rw = sc_.water.rhow, gx = sc_.gravity_x, gy = sc_.gravity_y;
    // The points in each cell (water_cell_points_): the material's cells, whose edges to
    // cells without points are its free faces (water_faces_row, and RESERVOIR's pressure in
    // load_forces). With the paper's mapping these are the cells holding mass; with MAPPING
    // SMOOTH a cell beside them may hold a sliver of a point's square, which is not
    // material: a reservoir's pressure on its nodes, of that sliver's mass, drove them 82 m
    // in the second step of drawdown.deck, and its faces were closed to the water.
    std::fill(water_cell_points_.begin(), water_cell_points_.end(), 0);
    for (std::size_t k = 0; k < p_.size(); ++k)
        if (p_.cell[k] >= 0) ++water_cell_points_[std::size_t(p_.cell[k])];
    if (!serial()) {  // the bands: water_rows_[j], the points in the rows of cells below row j
        for (int j = 0; j < my_; ++j) {  // (per cell first: a division per point cost more than the bands saved)
            long in = 0;
            for (int i = 0; i < mx_; ++i) in += water_cell_points_[std::size_t(cell(i, j))];
            water_rows_[std::size_t(j) + 1] = water_rows_[std::size_t(j)] + in;
        }
    }
    // 3 with MAPPING SMOOTH: each cell the point's square overlaps by its share (its rows b
    // and b + 1, in the band j0 .. j1-1), on V0 with ADVECT FLIP (smear_points); the paper's
    // mapping: in the second pass below
    auto smooth_stress = [&](std::size_t k, int j0, int j1) {
        const double vp = energy_volume(k) * p_.pw[k];
        const detail::Overlap& o = overlap_[k];
        if (o.b >= j1 || o.b + 1 < j0) return;
        each_part(o, [&](int ci, int cj, double, double, double wt) {
            if (cj < j0 || cj >= j1) return;
            const std::size_t a = std::size_t(cell(ci, cj));
            svxx_[a] -= wt * vp;
            svyy_[a] -= wt * vp;
        });
    };
    detail::WaterPoints w;
    w.n = p_.size(); w.cell = p_.cell.data(); w.group = p_.group.data(); w.gw = group_water_.data();
    w.x = p_.x.data(); w.y = p_.y.data(); w.vol = p_.vol.data(); w.pw = p_.pw.data(); w.wvol = p_.wvol.data();
    w.rw = rw; w.gx = gx; w.gy = gy; w.flow = flow; w.flip = flip; w.smooth = smooth;
    // The points of a band: those whose cells lie in its rows (a point outside the lattice:
    // the lowest band's).
    by_rows(my_, water_rows_, [&, w](int j0, int j1) {  // 1, and 2: each point's water into its cell's sums
        const int c0 = cell(0, j0), c1 = cell(0, j1);
        double *sv = wv_.data(), *sp = wp_.data(), *sk = wk_.data(), *sc = wc_.data(), *sq = wq_.data();
        if (flow)
            for (double* v : {sv, sp, sk, sc, sq}) std::fill(v + c0, v + c1, 0.0);
        detail::water_sums(w, c0, c1, j0 == 0, sv, sp, sk, sc, sq);
    });
    if (flow) water_flow();  // 2. the cells' exchange
    // 2. the pressure its cell's water now has at each point, and the stored energy that
    // took: on one thread summed at once, by threads kept per point (wde_) and summed after;
    // with the paper's mapping, 3: the total stress into eq. 8's sums
    const bool one = serial();
    double taken = d_water_;
    by_rows(my_, water_rows_, [&, w](int j0, int j1) {
        const int c0 = cell(0, j0), c1 = cell(0, j1);
        const double *sc = wc_.data(), *phi = wnew_.data();
        double *sxx = svxx_.data(), *syy = svyy_.data(), *de = wde_.data();
        const double dw = detail::water_pressures(w, c0, c1, sc, phi, sxx, syy, de, one, taken);
        if (one) taken = dw;
    });
    if (one) d_water_ = taken;
    else
        for (std::size_t k = 0; k < w.n; ++k)  // (0 where a point took none)
            if (w.gw[w.group[k]].kwn != 0 && w.cell[k] >= 0) d_water_ -= wde_[k];
    if (smooth) by_rows(my_, row_points_, [&](int j0, int j1) {
        for (std::size_t k = 0; k < p_.size(); ++k)
            if (p_.cell[k] >= 0 && group_water_[p_.group[k]].kwn != 0) smooth_stress(k, j0, j1);
    });
}

// 2. The cells' exchange, from the sums water_pass made: each cell's potential after it
// (wnew_: its net inflow dW makes Phi + dW / C, taken as (sum + dW) / C) and
// the water it let out through drains and free faces (wr_; drained_ sums them in cell
// order). Three passes over the rows of cells, each by threads: each cell's own k and Phi
// (a cell whose water is at or below zero pressure takes no part: no unsaturated flow);
// the flux across each edge between two wet cells (wqx_: its right edge, wqy_: its top;
// 0 where no water crosses); each cell's inflow, its edges' fluxes in the order one pass
// over the cells in row order would add them (the edge below, the edge on the left, its
// right and top edges), then its free faces and drains (water_faces_row).
inline void Simulation::water_flow() {
    const long cells = long(mx_) * my_;
    const double dt = sc_.dt_s;
    by_rows(kWaterRows, 0, my_, cells, [&](int j) {
        for (std::size_t c = std::size_t(cell(0, j)), e = c + std::size_t(mx_); c < e; ++c) {
            if (!(wq_[c] > 0)) wc_[c] = 0;
            if (wc_[c] == 0) continue;
            wkc_[c] = wk_[c] / wv_[c];
            wphi_[c] = wp_[c] / wc_[c];
        }
    });
    const std::size_t row = std::size_t(mx_);
    auto flux = [&](std::size_t a, std::size_t b) {  // from cell a to cell b, both wet
        const double ka = wkc_[a], kb = wkc_[b];
        const double t = std::min(ka + kb > 0 ? 2 * ka * kb / (ka + kb) : 0.0, std::min(wc_[a], wc_[b]) / (8 * dt));
        return t * (wphi_[a] - wphi_[b]) * dt;
    };
    by_rows(kWaterRows, 0, my_, cells, [&](int j) {
        for (int i = 0; i < mx_; ++i) {
            const std::size_t c = std::size_t(cell(i, j));
            const bool wet = wc_[c] != 0;
            wqx_[c] = wet && i + 1 < mx_ && wc_[c + 1] != 0 ? flux(c, c + 1) : 0.0;
            wqy_[c] = wet && j + 1 < my_ && wc_[c + row] != 0 ? flux(c, c + row) : 0.0;
        }
    });
    by_rows(kWaterRows, 0, my_, cells, [&](int j) { water_faces_row(j); });
    for (std::size_t c = 0; c < wr_.size(); ++c) drained_ += wr_[c];
}

// Each cell of row j: its potential after the exchange (wnew_) and what it let out (wr_).
inline void Simulation::water_faces_row(int j) {
    const double dt = sc_.dt_s, rw = sc_.water.rhow, gx = sc_.gravity_x, gy = sc_.gravity_y;
    const Water& w = sc_.water;
    const bool table = w.table > -std::numeric_limits<double>::infinity();
    const bool reservoir = sc_.reservoir.on;
    const double level = reservoir ? sc_.reservoir.at(time()) : 0.0;
    auto phi_edge = [&](double x, double y) { return (table ? std::max(0.0, -rw * gy * (w.table - y)) : 0.0) - rw * (gx * x + gy * y); };
    const std::size_t row = std::size_t(mx_);
    for (int i = 0; i < mx_; ++i) {
        const std::size_t c = std::size_t(cell(i, j));
        double d = 0, out = 0;
        if (wc_[c] != 0) {
            if (j > 0) d += wqy_[c - row];  // (a flux of 0 adds nothing: d is never -0)
            if (i > 0) d += wqx_[c - 1];
            d -= wqx_[c];
            d -= wqy_[c];
            const double pa = wphi_[c], ka = wkc_[c];
            const std::uint8_t e = drain_edges_[c];
            const double t = std::min(2 * ka, wc_[c] / (8 * dt));
            // free faces (edges to cells inside the lattice holding no point): below a reservoir's level
            // drained to it (its potential rho_w |g_y| level), else seepage faces: water under
            // pressure leaves to p = 0 at the face, none enters
            auto open = [&](bool inside, std::size_t b) { return inside && water_cell_points_[b] == 0; };
            auto face = [&](bool o, double xm, double ym) {
                if (!o) return;
                const bool under = reservoir && ym <= level;
                const double q = t * (pa - (under ? rw * -gy * level : -rw * (gx * xm + gy * ym))) * dt;
                if (!under && q <= 0) return;
                d -= q;
                out += q;
            };
            const double xc = (i + 0.5) * L_, yc = (j + 0.5) * L_;
            face(!(e & kEdgeTop) && open(j + 1 < my_, c + row), xc, (j + 1) * L_);
            face(!(e & kEdgeBottom) && open(j > 0, c - row), xc, j * L_);
            face(!(e & kEdgeLeft) && open(i > 0, c - 1), i * L_, yc);
            face(!(e & kEdgeRight) && open(i + 1 < mx_, c + 1), (i + 1) * L_, yc);
            auto drain = [&](double x, double y) {
                const double q = t * (pa - phi_edge(x, y)) * dt;
                d -= q;
                out += q;
            };
            if (e & kEdgeBottom) drain((i + 0.5) * L_, j * L_);
            if (e & kEdgeTop) drain((i + 0.5) * L_, (j + 1) * L_);
            if (e & kEdgeLeft) drain(i * L_, (j + 0.5) * L_);
            if (e & kEdgeRight) drain((i + 1) * L_, (j + 0.5) * L_);
        }
        wnew_[c] = wc_[c] != 0 ? (wp_[c] + d) / wc_[c] : 0.0;
        wr_[c] = out;
    }
}

// LOAD: each loaded point's force to the nodes of its cell: along its line by the linear
// weights of its position, across it all to the nearer line of nodes (a point a quarter
// cell inside gives the force back to the nodes it was taken from at step 0; the load
// moves to the next line of nodes when the surface has moved half a cell). After the
// nodal forces; load_work books its work after the step.
inline void Simulation::load_forces() {
    if (!modes_.loads) return;
    load_nodes_.clear();
    auto add = [&](std::size_t n, double fx, double fy) {
        fx_[n] += fx; fy_[n] += fy;
        load_fx_[n] += fx; load_fy_[n] += fy;
        if (!load_mark_[n]) { load_mark_[n] = 1; load_nodes_.push_back(std::int32_t(n)); }
    };
    if (sc_.reservoir.on) {  // RESERVOIR: each free face below the level, p_w L / 2 on each of its nodes, into the material
        const double level = sc_.reservoir.at(time()), rg = -sc_.water.rhow * sc_.gravity_y;
        auto bare = [&](int i, int j) { return water_cell_points_[std::size_t(cell(i, j))] == 0; };  // no point (water_pass)
        for (int j = 0; j < my_; ++j) {
            if (j * L_ >= level) break;
            for (int i = 0; i < mx_; ++i) {
                if (bare(i, j)) continue;
                const std::size_t n1 = std::size_t(node(i, j)), n2 = n1 + 1, n3 = n1 + std::size_t(mx_) + 1, n4 = n3 + 1;
                auto face = [&](bool open, double ym, std::size_t a, std::size_t b, double nx, double ny) {
                    const double f = 0.5 * L_ * rg * (level - ym);
                    if (!open || f <= 0) return;
                    add(a, f * nx, f * ny);
                    add(b, f * nx, f * ny);
                };
                const double yc = (j + 0.5) * L_;
                face(j + 1 < my_ && bare(i, j + 1), (j + 1) * L_, n3, n4, 0, -1);  // top
                face(j > 0 && bare(i, j - 1), j * L_, n1, n2, 0, 1);               // bottom
                face(i > 0 && bare(i - 1, j), yc, n1, n3, 1, 0);                   // left
                face(i + 1 < mx_ && bare(i + 1, j), yc, n2, n4, -1, 0);            // right
            }
        }
    }
    if (p_.load_x.empty()) return;
    for (std::size_t k = 0; k < p_.size(); ++k) {
        const double fx = p_.load_x[k], fy = p_.load_y[k];
        const int c = p_.cell[k];
        if ((fx == 0 && fy == 0) || c < 0) continue;
        const int i = c % mx_, j = c / mx_;
        double u = p_.x[k] * invL_ - i, v = p_.y[k] * invL_ - j;
        if (p_.load_axis[k] == 1) v = v < 0.5 ? 0.0 : 1.0;
        else u = u < 0.5 ? 0.0 : 1.0;
        const int n1 = node(i, j);
        const int at[4] = {n1, n1 + 1, n1 + mx_ + 1, n1 + mx_ + 2};
        const double w[4] = {(1 - u) * (1 - v), u * (1 - v), (1 - u) * v, u * v};
        for (int a = 0; a < 4; ++a) add(std::size_t(at[a]), w[a] * fx, w[a] * fy);
    }
}

inline void Simulation::load_work() {
    if (!modes_.loads) return;
    double w = 0, h = 0;
    for (const std::int32_t m : load_nodes_) {
        const std::size_t n = std::size_t(m);
        const double bx = dux_old_[n], by = duy_old_[n], cx = dux_[n], cy = duy_[n];
        w += 0.5 * (load_fx_[n] * (bx + cx) + load_fy_[n] * (by + cy));
        h = h + 0.5 * (load_fx_[n] * cx + load_fy_[n] * cy);
        load_fx_[n] = load_fy_[n] = 0;
        load_mark_[n] = 0;
    }
    w_loads_ += w;
    h_loads_ = h;
}

// ======================================================================================
// THE REFERENCE CYCLE
//
// One LPFDM step (paper section 2) as plainly as it can be written: one loop per phase
// over every cell, point and node, one value at a time, one thread. It is the definition
// of a step: the fast kernel below visits only the occupied part of the lattice, runs
// threads and AVX2 lanes, and gives the same numbers bit for bit (tests/test_reference.cpp
// runs every deck both ways). The equations themselves are the free functions above
// (cell_strain, jaumann_rotation, elastic_increment, mohr_coulomb_return, move_point_*,
// CellSums::add, smear_weight, add_cell_force, compensate_increment, damped_increment),
// which both kernels call.
//
// Where the paper is open, the choices made here (each tested in tests/):
// * Points move by eq. 7a/7b's affine map taken about the cell centre with the mean of the
//   four nodal increments (MOTION CENTRE, the default), not about node [1]: the paper's
//   map takes the cell's non-affine part from node [1] alone, so a mirror-symmetric scene
//   drifted to one side (a symmetric collapse ran out 9-16 % further to the right), and
//   a checkerboard of nodal increments, which eq. 5 does not see, carried points away.
//   MOTION PAPER (the paper's, about node [1]) and BILINEAR are options; MAPPING SMOOTH
//   takes BILINEAR by default (its strain is that field's gradient).
// * Eq. 12 uses the strain increments of the cell containing x_node - du_node; a
//   lookup outside the lattice or into an empty cell compensates nothing (an empty
//   cell has no strain: taken from nodes at rest beside moving ones, it made every
//   free surface brake and stretch, an instability seen in free fall). A node that had no mass in the
//   previous step has no increment of its own to compensate: it takes the mass-
//   weighted mean increment of its neighbours that had mass (the material arriving
//   brings its motion). With the paper's literal du = 0 a falling block is braked at
//   every new row of cells it enters (tests: free fall at exactly g).
//   Known: energy is not conserved exactly where stressed points cross cell edges. A 2 m
//   drop of a block 4 cells across rebounds to 1.21 of its height (dt 0.5 of the limit;
//   1.27 at 0.1); 8 cells across, to 0.87. The excess falls with L (tests/test_hard.cpp
//   gives the figures).
// ======================================================================================

LPFDM_DEF void Simulation::step_reference() {
    if (step_ == 0) start_energy();
    reference_cell_strains();  // eq. 5a-5f
    reference_points();        // eq. 6, Jaumann by eq. 5f, volume, eq. 7a/7b; eq. 7, 8
    water_pass();              // WATER: pore pressure, Darcy flow, total stress into eq. 8's sums
    reference_nodal_forces();  // eq. 8, virtual work transpose of eq. 5, gravity eq. 10
    load_forces();             // LOAD
    reference_compensate();    // eq. 12
    reference_integrate();     // eq. 13-14, fixed nodes, moving walls
    load_work();
    shift_points();  // SHIFT
    parked_ += parking_.take();
    held_ += holding_.take();
    ++step_;
    if (reorder_due()) reorder_points();  // storage only (REORDER), as step() does
}

// eq. 6 by a model the embedding program gave (set_user_model).
inline void Simulation::user_consult(const MaterialConstants& mc, std::size_t q, const StrainIncrement& e, Stress& s) {
    const bool plastic = modes_.plastic;
    PointState ps{plastic ? p_.plastic_shear[q] : 0.0, plastic && p_.yielded[q]};
    user_models_[std::size_t(mc.user)](e, s, ps);
    if (plastic) { p_.plastic_shear[q] = ps.plastic_shear; p_.yielded[q] = ps.yielded; }
}

// 1. eq. 5a-5f: each cell's strain increments and rotation from its four nodes' increments.
inline void Simulation::reference_cell_strains() {
    for (int j = 0; j < my_; ++j)
        for (int i = 0; i < mx_; ++i) {
            const int c = cell(i, j);
            CellStrain& s = strain_[std::size_t(c)];
            s = CellStrain{};  // an empty cell: no strain and no rotation (see eq. 12 at the head of this section)
            if (modes_.hourglass) hgx_[std::size_t(c)] = hgy_[std::size_t(c)] = 0;
            if (!(cmass_[std::size_t(c)] > 0)) continue;
            const StrainIncrement e = strain_of_cell(i, j);  // eq. 5a-5d
            s.xx = e.xx; s.yy = e.yy; s.xy = e.xy; s.yx = e.yx;
            jaumann_rotation(e.theta(), s.rc, s.rs);  // eq. 5e, 5f
            if (modes_.hourglass) checkerboard_mode(dux_.data(), duy_.data(), node(i, j), mx_ + 1, hgx_[std::size_t(c)], hgy_[std::size_t(c)]);
        }
}

// eq. 6: the stress of point k after its cell's strain increment e: the old stress turns
// with the material (Jaumann: (rc, rs) the cosine and sine of twice eq. 5f's rotation),
// then the constitutive model adds its increment (Hooke's law, then the Mohr-Coulomb
// return if the trial lies outside the yield surface; or the user's model).
inline void Simulation::consult_model(std::size_t k, const MaterialConstants& mc, const StrainIncrement& e, double rc, double rs, Stress& s) {
    if (mc.model == Model::User) {
        rotate_stress(s, rc, rs);
        user_consult(mc, k, e, s);
        return;
    }
    elastic_trial(s.xx, s.yy, s.xy, s.zz, elastic_change(mc, e), rc, rs);  // the elastic trial
    if (mc.model != Model::MohrCoulomb) return;
    modes_.scatter ? mohr_consult<true>(mc, k, p_.vol[k], s) : mohr_consult<false>(mc, k, p_.vol[k], s);
}

// eq. 7a/7b (or MOTION CENTRE, BILINEAR): where a point of cell (ci, cj) with the cell's
// strain increments e goes from (x0, y0); (dx, dy): its own increment (CENTRE, BILINEAR).
inline void Simulation::move_with_cell(int ci, int cj, const StrainIncrement& e, double x0, double y0, double& x, double& y, double& dx, double& dy) const {
    const double xi = ci * L_, yj = cj * L_;
    double ux[4], uy[4];
    gather_nodes(node(ci, cj), ux, uy);  // eq. 7a/7b's nodes
    if (modes_.motion == Motion::Paper) {
        move_point_paper(x0, y0, e, xi, yj, ux[0], uy[0], x, y);
    } else if (modes_.motion == Motion::Centre) {
        double umx, umy;
        mean_of_four(ux[0], ux[1], ux[2], ux[3], umx); mean_of_four(uy[0], uy[1], uy[2], uy[3], umy);
        move_point_centre(x0, y0, e, xi, yj, L_, umx, umy, x, y, dx, dy);
    } else {
        move_point_bilinear(x0, y0, xi, yj, invL_, ux, uy, x, y, dx, dy);
    }
}

// 2. The points, in storage order: eq. 6 and the volume change with the strain of the cell
// each lies in; eq. 7a/7b moves it with that cell; then, the lattice back at its original
// position, eq. 7 and 8 add its mass and V sigma to the cell it lies in now. A point that
// left the lattice leaves the cycle (its mass becomes outflow).
inline void Simulation::reference_points() {
    if (modes_.mapping == Mapping::Smooth) { reference_points_smooth(); return; }
    for (auto* v : {&cmass_, &cvol_, &svxx_, &svyy_, &svxy_}) std::fill(v->begin(), v->end(), 0.0);
    std::fill(carried_.begin(), carried_.end(), Carried{});
    double mass = 0;
    for (std::size_t k = 0; k < p_.size(); ++k) {
        const int c = p_.cell[k], ci = c % mx_, cj = c / mx_;
        const CellStrain& ce = strain_[std::size_t(c)];
        const StrainIncrement e{ce.xx, ce.yy, ce.xy, ce.yx};
        const Group& g = groups_[p_.group[k]];
        p_.vol[k] *= 1 + e.xx + e.yy;  // V (1 + d_eps_xx + d_eps_yy)
        Stress s{p_.sxx[k], p_.syy[k], p_.sxy[k], p_.szz[k]};
        consult_model(k, *group_consts_[p_.group[k]], e, ce.rc, ce.rs, s);  // eq. 6
        p_.sxx[k] = s.xx; p_.syy[k] = s.yy; p_.sxy[k] = s.xy; p_.szz[k] = s.zz;

        // eq. 7a/7b (or MOTION CENTRE, BILINEAR); (dx, dy): the point's own increment.
        const double x0 = p_.x[k], y0 = p_.y[k];
        double x = 0, y = 0, dx = 0, dy = 0;
        move_with_cell(ci, cj, e, x0, y0, x, y, dx, dy);
        stop_at_edges(c, x0, y0, x, y);
        p_.x[k] = x; p_.y[k] = y;

        const int cn = cell_holding(x, y);
        p_.cell[k] = cn;
        if (cn < 0) continue;  // left the lattice
        const int ni = cn % mx_, nj = cn / mx_;
        if (modes_.advect == Advect::Points) carry_to(cn, ni, nj, g.mass, x, y, dx, dy, e);  // ADVECT POINTS
        add_to_cell(std::size_t(cn), g.mass, std::min(p_.vol[k], g.vol0), s.xx, s.yy, s.xy);  // eq. 7, 8
        mass += g.mass;
    }
    remove_departed();
    mass_in_ = mass;
}

// 3. Nodal forces: eq. 8 smears each cell's sum V sigma; each node gathers the force of
// its (up to) four cells by the transpose of eq. 5, and gravity on its lumped mass, a
// quarter of each neighbouring cell's mass (eq. 10).
inline void Simulation::reference_nodal_forces() {
    const double L2 = L_ * L_, inv2L = 0.5 * invL_;
    for (std::size_t c = 0; c < cmass_.size(); ++c) {
        double w;
        smear_weight(cvol_[c], L2, inv2L, w);  // eq. 8
        svxx_[c] *= w; svyy_[c] *= w; svxy_[c] *= w;
        if (modes_.mapping == Mapping::Smooth) smooth_moment(c);
    }
    const double khg = sc_.hourglass * 0.25 / (sc_.dt_s * sc_.dt_s);
    for (int j = 0; j <= my_; ++j)
        for (int i = 0; i <= mx_; ++i) {
            double fx = 0, fy = 0, m = 0;
            const bool right = i < mx_, left = i > 0, above = j < my_, below = j > 0;
            const int c = j * mx_ + i;  // cell (i, j): the node is its [1], [2] of c - 1, [3] of c - mx, [4] of c - mx - 1
            auto cell_force = [&](int a, auto corner) {
                add_cell_force<decltype(corner)::value>(svxx_[std::size_t(a)], svyy_[std::size_t(a)], svxy_[std::size_t(a)], fx, fy);
                m += cmass_[std::size_t(a)];
            };
            if (right && above) cell_force(c, std::integral_constant<int, 1>{});
            if (left && above) cell_force(c - 1, std::integral_constant<int, 2>{});
            if (right && below) cell_force(c - mx_, std::integral_constant<int, 3>{});
            if (left && below) cell_force(c - mx_ - 1, std::integral_constant<int, 4>{});
            if (modes_.mapping == Mapping::Smooth) smooth_node_force(c, right, left, above, below, fx, fy);  // MAPPING SMOOTH
            if (modes_.hourglass) hourglass_node_force(c, right, left, above, below, khg, fx, fy);  // HOURGLASS
            const std::size_t n = std::size_t(node(i, j));
            const double mn = 0.25 * m;  // eq. 10
            nmass_prev_[n] = nmass_[n];
            nmass_[n] = mn;
            fx_[n] = fx + sc_.gravity_x * mn;
            fy_[n] = fy + sc_.gravity_y * mn;
        }
}

LPFDM_INLINE inline bool Simulation::strain_at(double fxs, double fys, const Range& box, double& exx, double& eyy, double& exy, double& eyx) const {
    int ci = int(fxs), cj = int(fys);  // floor without a library call (|du| < L/2)
    ci -= fxs < ci; cj -= fys < cj;
    // On a cell edge (a zero component of du) the cells on both sides share the look-up,
    // so that a mirror-symmetric motion stays symmetric.
    const int ci0 = fxs == ci ? ci - 1 : ci, cj0 = fys == cj ? cj - 1 : cj;
    auto inside = [&](int a, int b) { return a >= box.i0 && b >= box.j0 && a < box.i1 && b < box.j1; };
    const CellStrain* cs = strain_.data();
    if (ci0 == ci && cj0 == cj) {  // one cell
        if (!inside(ci, cj)) return false;
        const CellStrain& e = cs[cell(ci, cj)];
        exx = e.xx; eyy = e.yy; exy = e.xy; eyx = e.yx;
        return true;
    }
    if (inside(ci0, cj0) && inside(ci, cj)) {  // two or four cells, all counting (the usual case: one test)
        const CellStrain* a = cs + cell(ci0, cj0);
        exx = 0 + a->xx; eyy = 0 + a->yy; exy = 0 + a->xy; eyx = 0 + a->yx;  // the same sums as below
        if (ci0 != ci) { exx += a[1].xx; eyy += a[1].yy; exy += a[1].xy; eyx += a[1].yx; }
        if (cj0 != cj) {
            const CellStrain* b = a + mx_;
            exx += b->xx; eyy += b->yy; exy += b->xy; eyx += b->yx;
            if (ci0 != ci) { exx += b[1].xx; eyy += b[1].yy; exy += b[1].xy; eyx += b[1].yx; }
        }
        const double iw = ci0 != ci && cj0 != cj ? 0.25 : 0.5;
        exx *= iw; eyy *= iw; exy *= iw; eyx *= iw;
        return true;
    }
    exx = eyy = exy = eyx = 0;  // two or four cells, in row order, some outside the box
    double w = 0;
    auto add = [&](int a, int b) {
        if (!inside(a, b)) return;
        const CellStrain& e = cs[cell(a, b)];
        exx += e.xx; eyy += e.yy; exy += e.xy; eyx += e.yx; w += 1;
    };
    add(ci0, cj0);
    if (ci0 != ci) add(ci, cj0);
    if (cj0 != cj) { add(ci0, cj); if (ci0 != ci) add(ci, cj); }
    if (w == 0) return false;
    if (w == 2 || w == 4) {  // x / 2 and x * 0.5 are the same number
        const double iw = w == 2 ? 0.5 : 0.25;
        exx *= iw; eyy *= iw; exy *= iw; eyx *= iw;
    } else if (w > 1) {
        exx /= w; eyy /= w; exy /= w; eyx /= w;
    }
    return true;
}

// 4. eq. 12: the increment each node carries belonged to the material now at
// x_node - du_node; it is compensated by the strain increments of the cell found there.
// A node that gained mass this step takes the mass-weighted mean increment of its
// neighbours that had mass (see the head of this section). ADVECT POINTS replaces all of this, and
// ADVECT FLIP too: its transfer made the increments in the points' phase (flip_second_half).
inline void Simulation::reference_compensate() {
    if (modes_.advect == Advect::Flip) return;
    if (modes_.advect == Advect::Points) {
        for (int j = 0; j <= my_; ++j) carried_row(j, 0, mx_ + 1);
        return;
    }
    for (int j = 0; j <= my_; ++j)
        for (int i = 0; i <= mx_; ++i) {
            const std::size_t n = std::size_t(node(i, j));
            if (!gained_mass(nmass_prev_[n], nmass_[n])) continue;
            double sx = 0, sy = 0, msum = 0;
            for (int qj = std::max(0, j - 1); qj <= std::min(my_, j + 1); ++qj)
                for (int qi = std::max(0, i - 1); qi <= std::min(mx_, i + 1); ++qi) {
                    const std::size_t q = std::size_t(node(qi, qj));
                    const double mq = nmass_prev_[q];
                    if (mq > 0) { sx += mq * dux_[q]; sy += mq * duy_[q]; msum += mq; }
                }
            if (msum > 0) { dux_[n] = sx / msum; duy_[n] = sy / msum; }
        }
    for (int j = 0; j <= my_; ++j)
        for (int i = 0; i <= mx_; ++i) {
            const std::size_t n = std::size_t(node(i, j));
            double ux = dux_[n], uy = duy_[n], exx, eyy, exy, eyx;
            if ((ux == 0 && uy == 0) || nmass_prev_[n] == 0) continue;
            if (!strain_at(i - ux * invL_, j - uy * invL_, {0, mx_, 0, my_}, exx, eyy, exy, eyx)) continue;
            compensate_increment(ux, uy, exx, eyy, exy, eyx);  // eq. 12a, 12b
            dux_[n] = ux; duy_[n] = uy;
        }
}

// 5. eq. 13-14 at every node with mass (a node without mass does not move), then fixed
// directions and moving walls; the kinetic energy summed by rows, in node order.
inline void Simulation::reference_integrate() {
    if (modes_.advect == Advect::Flip) { flip_integrate(flip_nodes(), {0, mx_ + 1, 0, my_ + 1}); return; }  // ADVECT FLIP's own step 5 (its section)
    const double dt2 = sc_.dt_s * sc_.dt_s;
    if (modes_.dynamic) dynamics_begin();  // the ground's step, the boundary forces (SHAKE, ABSORB)
    keep_increments({0, mx_ + 1, 0, my_ + 1});  // for the energy account
    const bool window = !mean_ux_.empty();
    for (std::size_t n = 0; n < nmass_.size(); ++n) {
        if (nmass_[n] == 0) {  // no mass, no motion (and no mean motion: DAMPING WINDOW)
            dux_[n] = duy_[n] = 0;
            if (window) mean_ux_[n] = mean_uy_[n] = 0;
            continue;
        }
        if (window) { follow_mean(dux_[n], mean_beta_, mean_ux_[n]); follow_mean(duy_[n], mean_beta_, mean_uy_[n]); }  // DAMPING WINDOW
        damped_increment(dux_[n], fx_[n], nmass_[n], dt2, sc_.damping, dux_[n], mean_at(mean_ux_, n));  // eq. 13, 14
        damped_increment(duy_[n], fy_[n], nmass_[n], dt2, sc_.damping, duy_[n], mean_at(mean_uy_, n));
    }
    integrated_ = {0, mx_ + 1, 0, my_ + 1};
    if (modes_.dynamic) absorb_increments();  // the dashpots of ABSORB
    impose_supports();
    if (modes_.mapping == Mapping::Smooth) follow_material({0, mx_ + 1, 0, my_ + 1});  // MAPPING SMOOTH: the nodes beyond the material (its section)
    for (int j = 0; j <= my_; ++j) energy_row_terms(j, 0, mx_ + 1, std::false_type{});
    tally_energy(0, my_ + 1);
    nodal_kinetic({0, mx_ + 1, 0, my_ + 1});
}

// The nodes' kinetic energy (ke, at the last half step) summed by rows in node order, and
// the largest increment (the run's health check), over a box holding every node with mass.
inline void Simulation::nodal_kinetic(const Range& nodes) {
    const double dt2 = sc_.dt_s * sc_.dt_s;
    double ke = 0, maxdu = 0;
    for (int j = nodes.j0; j < nodes.j1; ++j) {
        double row_ke = 0;
        for (int i = nodes.i0; i < nodes.i1; ++i) {
            const std::size_t n = std::size_t(node(i, j));
            const double m = nmass_[n], ux = dux_[n], uy = duy_[n];
            if (m == 0) continue;
            row_ke += 0.5 * m * (ux * ux + uy * uy);
            maxdu = std::max(maxdu, std::max(std::fabs(ux), std::fabs(uy)));
        }
        ke += row_ke;
    }
    ke_ = ke / dt2;
    max_du_ = maxdu;
}

// ======================================================================================
// MAPPING SMOOTH
//
// Where the paper is open, the choices made here (each tested in tests/):
// * MAPPING SMOOTH (an option; the paper's mapping is the default): a point is the square
//   it stood for when made, and takes part in every cell the square overlaps in
//   proportion to the area inside it (square_overlap, GIMP's point domains). In each
//   such cell it sees the gradient of the cell's bilinear increment field at the centre
//   of its part (bilinear_gradient; at the cell centre that is eq. 5), and the nodal
//   forces are the exact transpose. Eq. 5's one gradient per cell would do at edges
//   inside the material but not at a free surface: a square reaching into a cell that
//   holds nothing else gives the two nodes beyond only its little mass and no support,
//   and their equilibrium then asks sigma = 0 of the point, so a loaded free surface
//   sheds its stress (verify_psc.deck read q 13 % low); the gradient at the part's centre
//   asks only for zero traction across the surface. The trace of each part's gradient is
//   taken at the centroid of the cell's material (B-bar: with 2 x 2 points per cell the
//   gradients at the points locked the near-incompressible plastic flow, q 10 % high).
//   Without gravity the wall of a plane-strain compression then reads the base reaction
//   within 2.8 % at every sample (the paper's mapping: spikes of 16 % each time the cap's
//   points cross the wall's line of nodes). The fast kernel runs the same per-point code
//   (smooth_move) by threads, with AVX2 four points at a time (smooth_lanes: the strain,
//   eq. 6's trial and the motion; the Mohr-Coulomb consult after, each_point_consulted;
//   squares_lanes: the cells and squares after the move), and adds eq. 7, 8 by threads
//   over bands of cell rows (smear_points; with AVX2 a cell's nine sums side by side,
//   smear_lanes): 2.8-6 times the paper's cost per particle-step on one thread
//   (tools/README.md), with limit loads no closer (the footing's +17 % at 4 cells under it,
//   against +10 %: its stiff points share the soil's cells at its edges), which is why
//   it is not the default.
// * A node none of whose cells holds a point (only the edges of squares reach it) has
//   eq. 10's mass but the share of stress the slivers' position gives it: it keeps the
//   weight that position gives it, and the rest of its mass follows the material beside
//   it (follow_material). Left alone, such nodes beside cohesionless sand at rest fell
//   for as long as the run went on.
// ======================================================================================

inline detail::Overlap Simulation::overlap_of(double x0, double y0, double l) const {
    detail::Overlap o;
    square_overlap(x0, l, L_, mx_, o.a, o.wx, o.cx);
    square_overlap(y0, l, L_, my_, o.b, o.wy, o.cy);
    return o;
}

template <class F> LPFDM_INLINE inline void Simulation::each_part(const detail::Overlap& o, F&& f) const {
    for (int q = 0; q < 2; ++q)
        for (int r = 0; r < 2; ++r) {
            const double w = o.wx[r] * o.wy[q];
            if (!(w > 0)) continue;
            f(o.a + r, o.b + q, o.cx[r], o.cy[q], w);
        }
}

LPFDM_DEF void Simulation::cell_centroid(std::size_t c, double& u, double& v) const {
    u = cvol_[c] > 0 ? smu_[c] / cvol_[c] : 0.0;
    v = cvol_[c] > 0 ? smv_[c] / cvol_[c] : 0.0;
}

LPFDM_DEF void Simulation::smooth_moment(std::size_t c) {
    const double L2 = L_ * L_;
    double w, cu, cv;
    smear_weight(cvol_[c], L2, 0.5 * invL_, w);  // eq. 8, as for the sums
    cell_centroid(c, cu, cv);
    const double p = 0.5 * (svxx_[c] + svyy_[c]);  // the sum of V p, times w
    shx_[c] = 2 * (w * shx_[c] + cv * p);
    shy_[c] = 2 * (w * shy_[c] + cu * p);
}

// 2, MAPPING SMOOTH: the same, with each point taking part in every cell its square
// overlaps, in proportion to the area inside it (square_overlap, GIMP's point domains).
// Its strain increments are the weighted sum over those cells of the gradient of the
// cell's bilinear increment field at the centre of the point's part in it (eq. 5 is that
// gradient at the cell centre), with the trace of each part's taken at the centroid of
// the cell's material (B-bar, see the head of this section); its rotation follows from them (eq. 5f),
// its motion is the weighted sum of each cell's eq. 7a/7b (or MOTION rule) at the centre
// of its part, and eq. 7, 8 share its mass and V sigma out by the weights at its new place.
//
// The sums over the parts are taken one axis at a time (GIMP's weights): the field is
// bilinear in each cell, so the mean over a square of a node's shape function is the
// product of two means along the axes (detail::axis_shape), and the mean of a gradient
// across an axis is the parts' fractions times the differences of the nodes (one cell's
// difference over L is its field's gradient across it). Nine nodes, not four for each of
// up to four parts; a rigid translation gives differences of exactly zero.
inline StrainIncrement Simulation::smooth_strain(const detail::Overlap& o, bool motion, double& dx, double& dy) const {
    double sx[3], sy[3];
    detail::axis_shape(o.a, o.wx, o.cx, L_, invL_, sx);
    detail::axis_shape(o.b, o.wy, o.cy, L_, invL_, sy);
    // Nodes a .. a + 2 of rows b .. b + 2 (past the lattice's edge a node of weight 0: the
    // square lies in cell a alone, and a node inside is read in its place).
    const int i0 = o.a, i1 = o.a + 1, i2 = std::min(o.a + 2, mx_);
    double ux[3][3], uy[3][3];
    for (int m = 0; m < 3; ++m) {
        const std::size_t n = std::size_t(std::min(o.b + m, my_) * (mx_ + 1));
        ux[m][0] = dux_[n + std::size_t(i0)]; ux[m][1] = dux_[n + std::size_t(i1)]; ux[m][2] = dux_[n + std::size_t(i2)];
        uy[m][0] = duy_[n + std::size_t(i0)]; uy[m][1] = duy_[n + std::size_t(i1)]; uy[m][2] = duy_[n + std::size_t(i2)];
    }
    StrainIncrement e;
    double mdx, mdy;
    detail::square_strain(sx, sy, o.wx, o.wy, ux, uy, invL_, e.xx, e.yy, e.xy, e.yx, mdx, mdy);
    if (motion) { dx = mdx; dy = mdy; }
    double trace = 0;  // B-bar: the parts' mean of the traces at their cells' centroids
    each_part(o, [&](int ci, int cj, double, double, double w) LPFDM_INLINE { trace += w * centroid_trace_[std::size_t(cell(ci, cj))]; });
    const double half_change = 0.5 * (trace - (e.xx + e.yy));
    e.xx += half_change; e.yy += half_change;
    return e;
}

// MAPPING SMOOTH, the B-bar part of smooth_strain: for each cell of `cells` that holds
// material, the trace of the gradient of its bilinear increment field at the centroid of
// that material (cell_centroid), the same for every part of a square in it. The points'
// parts all lie in cells holding material: their own squares put it there.
LPFDM_DEF void Simulation::centroid_traces(const Range& cells) {
    for (int j = cells.j0; j < cells.j1; ++j)
        for (int i = cells.i0; i < cells.i1; ++i) {
            const std::size_t c = std::size_t(cell(i, j));
            if (!(cmass_[c] > 0)) continue;
            const int n1 = node(i, j), n2 = n1 + 1, n3 = n1 + mx_ + 1, n4 = n3 + 1;
            const double ux[4] = {dux_[n1], dux_[n2], dux_[n3], dux_[n4]}, uy[4] = {duy_[n1], duy_[n2], duy_[n3], duy_[n4]};
            double cu, cv;
            cell_centroid(c, cu, cv);
            const StrainIncrement g = bilinear_gradient(ux, uy, 0.5 + cu, 0.5 + cv, invL_);
            centroid_trace_[c] = g.xx + g.yy;
        }
}

// MAPPING SMOOTH: the nodes that only the edges of points' squares reach. A point's square
// reaches up to half a cell past the cell holding it, and the cells it reaches take their
// share of its mass; eq. 10 gives each node a quarter of each of its cells' masses wherever
// the material lies in the cell, while the forces on it (the squares' moments) follow the
// material. A node none of whose cells holds a point (only slivers of squares reach it)
// then carries a quarter of the slivers' weight but only the share of their stress that
// their position gives it. Beside cohesionless sand at rest, whose points near the surface
// carry almost no stress, such nodes behind a smooth wall's face (2e-5 of a full node's
// mass) fell at (1 - alpha) g for as long as the run went on (eq. 12 carries a node's
// increment and found no strain in the empty cell above to compensate it with): the
// unbalanced-force ratio stayed at 4e-5, gravity's work on them showed as energy created
// (3 % by 20 s; 23 % on the same wall moved away 12 mm), and at 64 s one moved half a cell
// in a step, which the health check takes for an instability.
// So each such node is moved again, after eq. 13-14 and the supports, in each direction
// that no FIX, SHAKE or wall sets: of its mass m (eq. 10) the part m_w that its material's
// position gives it (the bilinear weights at the centroid of each of its cells' material,
// cell_centroid; the consistent load) keeps its weight, and the rest follows the material
// beside it, taking the mean acceleration a of its neighbours that a point's cell touches
// (by their mass, after their eq. 13-14 and supports) in place of g:
//   F' = F + (m - m_w) (a - g), then eq. 13-14 from the increment the step began with.
// At rest (a = 0) the node's weight is m_w g, which the slivers' stress carries; in free
// fall (a = g, no stress) F' = m g and it falls with the material at exactly g; without
// gravity it moves by its own forces as before, so a free surface keeps its load
// (verify_psc.deck's plateau moves by 1e-4). It reads those neighbours only and writes
// these nodes only, so the order does not matter. Each node of eq. 10's mass keeps it (the
// inertia; the consistent mass is unstable at the time step the material allows).
LPFDM_DEF void Simulation::follow_material(const Range& nodes) {
    auto holds = [&](int a, int b) { return a >= 0 && b >= 0 && a < mx_ && b < my_ && holds_point_[std::size_t(cell(a, b))]; };
    auto touched = [&](int i, int j) { return holds(i - 1, j - 1) || holds(i, j - 1) || holds(i - 1, j) || holds(i, j); };
    const double dt2 = sc_.dt_s * sc_.dt_s;
    for (int j = nodes.j0; j < nodes.j1; ++j)
        for (int i = nodes.i0; i < nodes.i1; ++i) {
            const std::size_t n = std::size_t(node(i, j));
            const double m = nmass_[n];
            if (m == 0 || touched(i, j)) continue;
            // m_w: its weight as the material's position gives it, the bilinear weights at the
            // centroid of each of its cells' material (cell_centroid)
            double mw = 0;
            auto weight = [&](int a, int b, double su, double sv) {
                if (a < 0 || b < 0 || a >= mx_ || b >= my_) return;
                const std::size_t c = std::size_t(cell(a, b));
                if (!(cmass_[c] > 0)) return;
                double u, v;
                cell_centroid(c, u, v);
                mw += cmass_[c] * (0.5 + su * u) * (0.5 + sv * v);
            };
            weight(i, j, -1, -1); weight(i - 1, j, 1, -1); weight(i, j - 1, -1, 1); weight(i - 1, j - 1, 1, 1);
            // the material's acceleration: its neighbours' that a point's cell touches
            double ax = 0, ay = 0, msum = 0;
            for (int b = std::max(0, j - 1); b <= std::min(my_, j + 1); ++b)
                for (int a = std::max(0, i - 1); a <= std::min(mx_, i + 1); ++a) {
                    const std::size_t q = std::size_t(node(a, b));
                    if (q == n || nmass_[q] == 0 || !touched(a, b)) continue;
                    ax += nmass_[q] * (dux_[q] - dux_old_[q]); ay += nmass_[q] * (duy_[q] - duy_old_[q]); msum += nmass_[q];
                }
            if (!(msum > 0)) continue;
            ax /= msum * dt2; ay /= msum * dt2;
            const double excess = m - mw;  // the part of eq. 10's mass its material's position does not give it
            const double fx = fx_[n] + excess * (ax - sc_.gravity_x), fy = fy_[n] + excess * (ay - sc_.gravity_y);
            const std::uint8_t held = std::uint8_t(fixed_[n] | driven_[n]);
            if (!(held & kFixX)) { fx_[n] = fx; damped_increment(dux_old_[n], fx, m, dt2, sc_.damping, dux_[n], mean_at(mean_ux_, n)); }  // eq. 13, 14
            if (!(held & kFixY)) { fy_[n] = fy; damped_increment(duy_old_[n], fy, m, dt2, sc_.damping, duy_[n], mean_at(mean_uy_, n)); }
        }
}

// One point of MAPPING SMOOTH's pass: its strain, stress and volume, and where it goes.
// It reads the nodes' increments, the cells' strains (the motion rule) and the centroids
// of the sums the last step left (the points where they are now), and writes point k
// only: the fast kernel runs it on the points by threads.
template <bool Trial> inline void Simulation::smooth_move(std::size_t k) {
    const double x0 = p_.x[k], y0 = p_.y[k];
    const detail::Overlap& o = overlap_[k];
    const bool bilinear = modes_.motion == Motion::Bilinear;
    double dx = 0, dy = 0;
    StrainIncrement e = smooth_strain(o, bilinear, dx, dy);  // eq. 5 as the point sees it
    if (!bilinear)  // each part moves by its cell's rule (eq. 7a/7b or MOTION CENTRE) at its centre
        each_part(o, [&](int ci, int cj, double px, double py, double w) LPFDM_INLINE {
            const CellStrain& ce = strain_[std::size_t(cell(ci, cj))];
            double x = 0, y = 0, ddx = 0, ddy = 0;
            move_with_cell(ci, cj, {ce.xx, ce.yy, ce.xy, ce.yx}, px, py, x, y, ddx, ddy);
            dx += w * (x - px); dy += w * (y - py);
        });
    if (modes_.advect == Advect::Flip) { e.xx *= 0.5; e.yy *= 0.5; e.xy *= 0.5; e.yx *= 0.5; }  // the first half (flip_second_half)
    smooth_stress<Trial>(k, e);
    double x = x0 + dx, y = y0 + dy;
    if (fixed_edges_[std::size_t(p_.cell[k])]) stop_at_edges(p_.cell[k], x0, y0, x, y);  // as in reference_points (a cell with no fixed edge stops nothing)
    p_.x[k] = x; p_.y[k] = y;
}

// Each point's square where it is (overlap_), unless the map left them so.
inline void Simulation::known_overlaps() {
    if (overlaps_known_) return;
    each_point([&](std::size_t k) { overlap_[k] = overlap_of(p_.x[k], p_.y[k], groups_[p_.group[k]].half); });
    overlaps_known_ = true;
}

// Point k's stress and volume by the strain increment e: its rotation (eq. 5f), the
// volume change and eq. 6. Trial: a Mohr-Coulomb point keeps consult_model's elastic
// trial, consulted afterwards with its block (each_point_consulted).
template <bool Trial> inline void Simulation::smooth_stress(std::size_t k, const StrainIncrement& e) {
    double rc, rs;
    jaumann_rotation(e.theta(), rc, rs);  // eq. 5f
    p_.vol[k] *= 1 + e.xx + e.yy;
    Stress s{p_.sxx[k], p_.syy[k], p_.sxy[k], p_.szz[k]};
    const MaterialConstants& mc = *group_consts_[p_.group[k]];
    if (Trial && mc.model == Model::MohrCoulomb) elastic_trial(s.xx, s.yy, s.xy, s.zz, elastic_change(mc, e), rc, rs);
    else consult_model(k, mc, e, rc, rs, s);  // eq. 6
    p_.sxx[k] = s.xx; p_.syy[k] = s.yy; p_.sxy[k] = s.xy; p_.szz[k] = s.zz;
}

// f(b0, b1) for the blocks of kConsultBlock points (the last one shorter), where f writes
// its block's points' own values only: by threads as each_point, in order otherwise.
template <class F> inline void Simulation::each_block(const F& f) {
    const long n = long(p_.size()), blocks = (n + kConsultBlock - 1) / kConsultBlock;
    auto block = [&](long b) { f(b * kConsultBlock, std::min(n, (b + 1) * kConsultBlock)); };
#if defined(_OPENMP)
    if (!serial()) {
        LPFDM_OMP(omp parallel for schedule(static) num_threads(team_))
        for (long b = 0; b < blocks; ++b) block(b);
        return;
    }
#endif
    for (long b = 0; b < blocks; ++b) block(b);
}

// f(k, trial) for every point k, where f writes point k's own values only and runs
// smooth_stress<trial>: smooth_move (Move) or flip_second_strain (not Move). As
// each_point with trial false; in the fast kernel with AVX2 and no user's model, by
// blocks of kConsultBlock points, each block's trials four points at a time
// (smooth_lanes, where it applies: with MOTION BILINEAR for smooth_move; else f with
// trial true), its Mohr-Coulomb points then consulted four at a time (consult_points,
// the AVX2 loop's consult): the same numbers.
template <bool Move, class F> inline void Simulation::each_point_consulted(const F& f) {
#if LPFDM_WIDE
    const bool lanes = !Move || modes_.motion == Motion::Bilinear;
    if (wide_ && no_user_groups_ && (mohr_groups_ || lanes)) {
        each_block([&](long b0, long b1) {
            if (lanes) smooth_lanes<Move>(b0, b1);
            else
                for (long k = b0; k < b1; ++k) f(std::size_t(k), std::true_type{});
            if (mohr_groups_) consult_points(b0, b1);
        });
        return;
    }
#endif
    each_point([&](std::size_t k) { f(k, std::false_type{}); });
}

// MAPPING SMOOTH's eq. 7 and 8 for every point where it now is, in point order, into
// sums cleared before; a point that left the lattice leaves the cycle. t: the cells
// touched, the mass inside.
inline void Simulation::smooth_map(Landing& t) {
    // Each point's cell and square where it is now (each point its own: by threads). A
    // point that left, or is not finite (remove_departed keeps it for the guard), has no parts.
    auto one = [&](std::size_t k) {
        const double x = p_.x[k], y = p_.y[k];
        p_.cell[k] = cell_holding(x, y);
        overlap_[k] = p_.cell[k] >= 0 ? overlap_of(x, y, groups_[p_.group[k]].half) : detail::Overlap{};
    };
#if LPFDM_WIDE
    if (wide_) each_block([&](long b0, long b1) { squares_lanes(b0, b1, one); });
    else
#endif
        each_point(one);
    // The mass inside, in point order, and follow_material's flags: the cells holding a point.
    // (Local pointers and a local sum: a store through holds_point_'s bytes may alias anything,
    // and would reload every member at every point.)
    std::fill(holds_point_.begin(), holds_point_.end(), std::uint8_t(0));
    const std::int32_t* cell = p_.cell.data();
    const std::uint16_t* group = p_.group.data();
    const Group* groups = groups_.data();
    std::uint8_t* holds = holds_point_.data();
    double mass = t.mass;
    long departed = 0;
    for (std::size_t k = 0, n = p_.size(); k < n; ++k) {
        const int c = cell[k];
        if (c < 0) { ++departed; continue; }
        mass += groups[group[k]].mass;
        holds[c] = 1;
    }
    t.mass = mass;
    t.departed += departed;
    if (t.departed) {  // the squares kept as remove_departed keeps the points
        std::size_t w = 0;
        for (std::size_t k = 0; k < p_.size(); ++k)
            if (p_.cell[k] >= 0 || !(std::isfinite(p_.x[k]) && std::isfinite(p_.y[k]))) overlap_[w++] = overlap_[k];
        remove_departed();
    }
    mass_in_ = t.mass;
    overlaps_known_ = true;
    if (!serial()) {  // by_rows' bands: row_points_[j], the points whose squares start below row j
        std::fill(row_points_.begin(), row_points_.end(), 0);
        for (std::size_t k = 0; k < p_.size(); ++k) ++row_points_[std::size_t(overlap_[k].b) + 1];
        for (std::size_t j = 1; j < row_points_.size(); ++j) row_points_[j] += row_points_[j - 1];
    }
    if (modes_.advect == Advect::Flip) smear_points<Smear::Mass>(t);  // eq. 7, 8 (the stress's in flip_second_half)
    else smear_points<Smear::All>(t);  // eq. 7, 8
}

// eq. 7 and 8 for every point whose square overlap_ holds (smear_point), in point order,
// into sums cleared before; t: the cells touched. ADVECT FLIP: V sigma on V0
// (flip_transfer), the centroids still weighted by V. The fast kernel's threads share the
// rows of cells out, each adding every point's parts in its own rows in point order: each
// cell takes the terms it takes on one thread, in the same order.
template <Simulation::Smear S> inline void Simulation::smear_points(Landing& t) {
    const bool flip = modes_.advect == Advect::Flip;
    auto rows = [&](int j0, int j1, Landing& u) {
#if LPFDM_WIDE
        if (wide_) { smear_lanes<S>(j0, j1, u); return; }
#endif
        for (std::size_t k = 0; k < p_.size(); ++k) {
            const detail::Overlap& o = overlap_[k];
            if (o.b >= j1 || o.b + 1 < j0) continue;  // its square's rows are b and b + 1
            const Group& g = groups_[p_.group[k]];
            const double v = std::min(p_.vol[k], g.vol0);
            if constexpr (S == Smear::Mass) smear_point<S>(o, g.mass, v, 0, 0, 0, j0, j1, u);
            else {
                const double r = flip && v > 0 ? g.vol0 / v : 1.0;  // (r * s is s when r is 1)
                smear_point<S>(o, g.mass, v, r * p_.sxx[k], r * p_.syy[k], r * p_.sxy[k], j0, j1, u);
            }
        }
    };
    by_rows(my_, [&](int j0, int j1) {
        Landing u;
        rows(j0, j1, u);
        LPFDM_OMP(omp critical)
        t.merge(u);
    });
}

// f(j0, j1) for bands of the rows 0 .. n-1 (of cells or nodes) that together hold them
// all: in the fast kernel's threaded point pass, a band a thread, the bands splitting
// the points evenly by counts[j], the points below row j (row_points_: by the first row of
// their squares, smooth_map; water_rows_: by their cells' rows, water_pass); one band
// otherwise. f adds every point's terms in its rows, in point order, so every cell or
// node takes the terms it takes on one thread, in the same order.
template <class F> inline void Simulation::by_rows(int n, [[maybe_unused]] const std::vector<long>& counts, const F& f) {
#if defined(_OPENMP)
    if (!serial()) {
        const long points = long(p_.size());
        LPFDM_OMP(omp parallel num_threads(team_))
        {
            const int nt = omp_get_num_threads(), id = omp_get_thread_num();
            auto band = [&](int u) {  // the first row of thread u's band
                if (u >= nt) return n;
                int j = 0;
                while (j < n && counts[std::size_t(std::min(j, my_))] < points * u / nt) ++j;
                return j;
            };
            f(band(id), band(id + 1));
        }
        return;
    }
#endif
    f(0, n);
}

inline void Simulation::reference_points_smooth() {
    centroid_traces(Range{0, mx_, 0, my_});
    known_overlaps();
    for (std::size_t k = 0; k < p_.size(); ++k) smooth_move<false>(k);
    for (auto* v : {&cmass_, &cvol_, &svxx_, &svyy_, &svxy_, &shx_, &shy_, &smu_, &smv_}) std::fill(v->begin(), v->end(), 0.0);
    Landing t;
    smooth_map(t);
    if (modes_.advect == Advect::Flip) flip_second_half(flip_nodes(), {0, mx_, 0, my_});
}

// eq. 7 and 8 for a point whose square is o, MAPPING SMOOTH: its mass m and V sigma shared out
// among the cells its square overlaps, and the moments of both about each cell's centre;
// the parts in rows j0 .. j1-1 only (smear_points' threads).
template <Simulation::Smear S> inline void Simulation::smear_point(const detail::Overlap& o, double m, double v, double sxx, double syy, double sxy, int j0, int j1, Landing& t) {
    const double p = 0.5 * (sxx + syy);
    each_part(o, [&](int ci, int cj, double px, double py, double w) LPFDM_INLINE {
        if (cj < j0 || cj >= j1) return;
        const std::size_t c = std::size_t(cell(ci, cj));
        const double ru = (px - ci * L_) * invL_ - 0.5, rv = (py - cj * L_) * invL_ - 0.5;
        const double wv = w * v;
        if constexpr (S != Smear::Stress) {
            t.cmin = std::min(t.cmin, int(c)); t.cmax = std::max(t.cmax, int(c));
            t.imin = std::min(t.imin, ci); t.imax = std::max(t.imax, ci);
        }
        if constexpr (S == Smear::All) add_to_cell(c, w * m, wv, sxx, syy, sxy);
        else {  // add_to_cell's terms, less those the mapping leaves out
            if constexpr (S == Smear::Mass) cmass_[c] += w * m;
            cvol_[c] += wv;
            if constexpr (S == Smear::Stress) { svxx_[c] += wv * sxx; svyy_[c] += wv * syy; svxy_[c] += wv * sxy; }
        }
        if constexpr (S != Smear::Mass) {
            shx_[c] += wv * ((sxx - p) * rv + sxy * ru);
            shy_[c] += wv * (sxy * rv + (syy - p) * ru);
        }
        smu_[c] += wv * ru;
        smv_[c] += wv * rv;
    });
}

// MAPPING SMOOTH's point phase in the fast kernel: reference_points_smooth, with the
// points' first pass (smooth_move, each point on its own) by threads, the cells cleared
// in the box the last step's points touched, and the box they touch now kept for the
// lattice phases; ADVECT FLIP's transfer and second half on the boxes of flip_nodes and
// those cells.
inline void Simulation::smooth_point_pass() {
    centroid_traces(strained_);  // the cells around those holding material (cell_strains)
    known_overlaps();
    each_point_consulted<true>([&](std::size_t k, auto trial) { smooth_move<decltype(trial)::value>(k); });
    clear_cells();
    Landing t;
    smooth_map(t);
    departed_ = std::size_t(t.departed);
    occupied_ = landed(t);
    parts_known_ = false;
    if (modes_.advect == Advect::Flip) flip_second_half(flip_nodes(), occupied_);  // ADVECT FLIP's transfer
}

// reference_nodal_forces' share of MAPPING SMOOTH at the node that is corner [1] of cell c
// (which of its four cells exist: right, left, above, below): F[a] -= s_x s_y (shx, shy) / L,
// s = the corner's signs of b.
LPFDM_INLINE inline void Simulation::smooth_node_force(int c, bool right, bool left, bool above, bool below, double& fx, double& fy) const {
    auto moment = [&](int a, double h) { fx -= h * shx_[std::size_t(a)]; fy -= h * shy_[std::size_t(a)]; };
    if (right && above) moment(c, 1);
    if (left && above) moment(c - 1, -1);
    if (right && below) moment(c - mx_, -1);
    if (left && below) moment(c - mx_ - 1, 1);
}

// ======================================================================================
// ADVECT FLIP
//
// Where the paper is open, the choices made here (each tested in tests/):
// * ADVECT FLIP (an option, with MAPPING SMOOTH) replaces eq. 12 by a transfer that
//   neither loses nor makes energy: each point keeps its own increment, the lattice is
//   made from them with GIMP's weights, its change goes back to them, the stress takes
//   half its strain from each lattice of the step and works on the initial volume. An
//   undamped dropped block keeps its energy account within 0.11 % (eq. 12: 10-70 %).
//   Every kernel runs it: the fast kernel on the boxes its points touch, each point's own
//   work by threads, every sum in point order. See Simulation::flip_transfer.
// ======================================================================================

// ADVECT FLIP (MAPPING SMOOTH, MOTION BILINEAR). Each point p
// keeps an increment of its own, d_p (its velocity times dt). Node n's share of point p,
// w_np (flip_weights), is GIMP's: the mean over p's square of n's bilinear function, the
// transpose of the interpolation by which the point moves. A step:
//   1. the points take half of their strain from the last lattice increment c where they
//      are (smooth_move), move by c and are mapped (eq. 7, 8);
//   2. the transfer, in eq. 12's place: b_n = sum_p w_np m_p d_p / M_n, M_n = sum_p w_np m_p
//      (a held direction: its support's last increment); the points take the other half
//      of their strain from b where they are now and are mapped again (flip_second_half);
//   3. eq. 8's forces F (eq. 10's masses m_n), then eq. 13-14 on the transfer's masses:
//      a_n = eq13(b_n, F_n + g (M_n - m_n), M_n) - b_n (flip_changes); the supports see
//      b_n + a_n as eq. 13's increment, and a direction they hold (fixed, or driven by a
//      wall to d) takes a_n = d - b_n instead; the points take the change where they are,
//      d_p += g_p = sum_n w_np a_n, and the lattice moves by what they will bring back,
//      c_n = b_n + sum_p w_np m_p g_p / M_n, the held directions at d (flip_return).
// Why each part (each measured on an undamped elastic block dropped on a fixed floor,
// tests/README.md):
//   - the points keep their increments: eq. 12 and any remaking of the points' motion
//     from the lattice (PIC) lose kinetic energy at each transfer;
//   - the lattice moves by the image of a that the points bring back, not by a itself:
//     it gets back only that image at the next transfer, and the difference is lost in
//     flight;
//   - the strain energy, eq. 8's V sigma and the plastic work on the initial volume V0 (the
//     stress read as Kirchhoff's, V sigma = V0 tau; the centroids keep min(V, V0)): energy
//     on min(V, V0) is not the potential of forces on the volume that changes, and impacts
//     made energy;
//   - half the strain from the old lattice, half from the new: a stress made from one
//     lattice's increment and forces working on the next lose energy at first order in dt;
//   - a held direction's change brought to the points: with eq. 13's own change there
//     (the material pushing back) the points under a wall moved up while the lattice moved
//     them down, and the next step undid a compression;
//   - a held direction starts from its support's last increment, not the points': from
//     theirs, the points beside a wall took d - b every step through the weights, which
//     damped them (an undamped column compressed by a wall lost 8.6 % of the wall's work;
//     now its account ends at 2.7e-5 of the energy in play); never giving the points the
//     wall's change (b = d always) left them behind the lattice, and lost 38 %.
// The kinetic energy of the account is the points' leapfrog product, sum_p m_p d_p(old) .
// d_p(new) / 2 dt^2. The supports read M_n and F_n + g (M_n - m_n) (inertia): the
// reactions, the supports' work, and a wall's force, M_n (d - b_n) / dt^2 - F_n, which
// includes its impact where it takes a node (a node a wall drove in the last step has
// b_n = d unless the wall changed speed). An impact loses energy: its change reaches the
// points through the weights, sum_p m_p g_p^2 <= sum_n M_n a_n^2, at most the kinetic
// energy it gives them (second order in the change). A support that changes speed every
// step (SHAKE's ground) loses more, at first order: its held direction starts from its
// own last increment, and the material beside it moves otherwise; the account names that
// as the supports' slip, d_slip (flip_slip). The dashpots' and the input traction's work
// is counted on the increments the points bring back (absorb_work). So the account of a
// shaken column closes to 5e-4 of the ground's work at 20 cells over H, a compliant base
// to 1e-6 (test_quake.cpp).

// f(n, w_np) for the nodes a .. a + 2 of rows b .. b + 2 of point k's square, in row
// order: the product of the two axes' means of the shape functions over the square
// (axis_shape, as smooth_strain's motion). Past the lattice's edge a node has weight 0,
// and the node inside is visited in its place (with 0: no branch on where a square lies).
// (Rows j0 .. j1-1 only: by_rows' bands.)
template <class F> LPFDM_INLINE inline void Simulation::flip_weights(std::size_t k, const F& f, int j0, int j1) const {
    const detail::Overlap& o = overlap_[k];
    if (o.b >= j1 || o.b + 2 < j0) return;  // none of its rows b .. b + 2 in the band (another thread's)
    double sx[3], sy[3];
    detail::axis_shape(o.a, o.wx, o.cx, L_, invL_, sx);
    detail::axis_shape(o.b, o.wy, o.cy, L_, invL_, sy);
    const int i2 = std::min(o.a + 2, mx_) - o.a, rows[3] = {o.b, o.b + 1, std::min(o.b + 2, my_)};
    for (int j = 0; j < 3; ++j) {
        if (rows[j] < j0 || rows[j] >= j1) continue;
        const std::size_t n = std::size_t(node(o.a, rows[j]));
        f(n, sx[0] * sy[j]);
        f(n + 1, sx[1] * sy[j]);
        f(n + std::size_t(i2), sx[2] * sy[j]);
    }
}

// FLIP's loops over nodes visit a box `nodes` that holds every node with mass or an
// increment, before and after the step (the reference cycle: the whole lattice; the fast
// kernel: flip_nodes); every node outside it has none of either, and a sum over it of
// zeros is the same bits. Its loops over points take them one at a time, or by threads
// where each point's result is its own (each_point); its sums take their terms in point
// order, one thread.

// Zeros in the box r of each array, rows of `stride` (mx_ + 1 for nodes, mx_ for cells).
inline void Simulation::zero_rows(const Range& r, int stride, std::initializer_list<std::vector<double>*> arrays) {
    if (r.empty()) return;
    for (int j = r.j0; j < r.j1; ++j)
        for (auto* v : arrays) std::fill(v->data() + std::size_t(j) * std::size_t(stride) + std::size_t(r.i0), v->data() + std::size_t(j) * std::size_t(stride) + std::size_t(r.i1), 0.0);
}

// f(k) for every point k, where f writes point k's own values only: by threads in the
// fast kernel's threaded point pass (serial(): not in the reference cycle, one thread, 4
// 096 points or fewer, a user's model), in point order otherwise; the same numbers.
template <class F> inline void Simulation::each_point(const F& f) {
    const long n = long(p_.size());
#if defined(_OPENMP)
    if (!serial()) {
        LPFDM_OMP(omp parallel for schedule(static) num_threads(team_))
        for (long k = 0; k < n; ++k) f(std::size_t(k));
        return;
    }
#endif
    for (long k = 0; k < n; ++k) f(std::size_t(k));
}

// The fast kernel's box for FLIP: the nodes of the cells the points' squares touch now
// (occupied_, as the points' phase left it), and those the last step left an increment
// at (live_nodes_: its points' nodes and the walls').
inline Range Simulation::flip_nodes() const {
    const Range now{occupied_.i0, occupied_.empty() ? 0 : occupied_.i1 + 1, occupied_.j0, occupied_.empty() ? 0 : occupied_.j1 + 1};
    return reference_only() ? Range{0, mx_ + 1, 0, my_ + 1} : now.unite(live_nodes_);
}

namespace detail {
// The first double of v at a 32-byte boundary (v holds four more than its records need):
// records of four doubles then lie in one AVX2 register's load, never across a cache line.
inline double* aligned32(std::vector<double>& v) {
    const std::uintptr_t at = reinterpret_cast<std::uintptr_t>(v.data());
    return v.data() + (32 - at % 32) % 32 / sizeof(double);
}
}  // namespace detail

// FLIP's sums over the points into the nodes of the box `nodes` (zeroed first): to0[n] =
// sum_p w_np m_p vx_p, to1 the same of vy, to2 (unless null) sum_p w_np m_p, each node's
// terms in point order (flip_weights), by threads over bands of rows. With AVX2 the three
// go side by side (flip_sums_lanes) and are copied out after: the same terms in the same
// order, so the same bits.
inline void Simulation::flip_sums(const Range& nodes, const double* vx, const double* vy, double* to0, double* to1, double* to2) {
    const std::size_t row = std::size_t(mx_ + 1);
    auto each_node = [&](const auto& f) {
        for (int j = nodes.j0; j < nodes.j1; ++j)
            for (int i = nodes.i0; i < nodes.i1; ++i) f(std::size_t(j) * row + std::size_t(i));
    };
#if LPFDM_WIDE
    if (wide_) {
        double* rec = detail::aligned32(flip_rec_);
        each_node([&](std::size_t n) { rec[4 * n] = rec[4 * n + 1] = rec[4 * n + 2] = rec[4 * n + 3] = 0; });
        by_rows(my_ + 1, [&](int j0, int j1) { flip_sums_lanes(j0, j1, rec, vx, vy); });
        each_node([&](std::size_t n) {
            to0[n] = rec[4 * n]; to1[n] = rec[4 * n + 1];
            if (to2) to2[n] = rec[4 * n + 2];
        });
        return;
    }
#endif
    each_node([&](std::size_t n) { to0[n] = to1[n] = 0; if (to2) to2[n] = 0; });
    by_rows(my_ + 1, [&](int j0, int j1) {
        for (std::size_t k = 0; k < p_.size(); ++k) {
            const double m = groups_[p_.group[k]].mass, ux = vx[k], uy = vy[k];
            flip_weights(k, [&](std::size_t n, double w) LPFDM_INLINE {
                to0[n] += w * m * ux; to1[n] += w * m * uy;
                if (to2) to2[n] += w * m;
            }, j0, j1);
        }
    });
}

// 2: b_n and M_n from the points' increments where they are now.
inline void Simulation::flip_transfer(const Range& nodes) {
    // The supports' increments of the last step: the walls', and the fixed nodes' (0, or
    // the ground's under SHAKE); a node both holds has one increment.
    for (const auto* list : {&driven_nodes_, &fixed_nodes_})
        for (const std::int32_t u : *list) {
            flip_sx_[std::size_t(u)] = dux_[std::size_t(u)];
            flip_sy_[std::size_t(u)] = duy_[std::size_t(u)];
        }
    flip_sums(nodes, p_.flip_ux.data(), p_.flip_uy.data(), dux_.data(), duy_.data(), flip_mass_.data());
    for (int j = nodes.j0; j < nodes.j1; ++j)
        for (int i = nodes.i0; i < nodes.i1; ++i) {
            const std::size_t n = std::size_t(node(i, j));
            if (flip_mass_[n] > 0) { dux_[n] /= flip_mass_[n]; duy_[n] /= flip_mass_[n]; }
        }
    // A support's direction takes nothing from the points: it starts from its support's
    // last increment, 0 at a fixed node (the ground's under SHAKE) and the wall's at a
    // node a wall drove in the last step. (A node a wall takes for the first time starts
    // from the points' increment, and the points take the change to the wall's: an impact.)
    // The points' own increment there is kept for the account (flip_slip), where the
    // support can change speed: a shaken direction of a fixed node, a wall's (a fixed
    // direction at rest has a = 0 - 0, no term).
    flip_held_.clear();  // capacity reserved at set-up: no allocation
    const std::uint8_t shaken = shaken_dirs();
    auto start_from_support = [&](std::int32_t u, std::uint8_t dirs, std::uint8_t kept) {
        const std::size_t n = std::size_t(u);
        if (kept) flip_held_.push_back({u, kept, dux_[n], duy_[n]});
        if (dirs & kFixX) dux_[n] = flip_sx_[n];
        if (dirs & kFixY) duy_[n] = flip_sy_[n];
    };
    for (const std::int32_t u : fixed_nodes_) start_from_support(u, fixed_[std::size_t(u)], fixed_[std::size_t(u)] & shaken);
    const std::size_t walls_from = flip_held_.size();
    for (const std::int32_t u : driven_nodes_) start_from_support(u, driven_[std::size_t(u)], driven_[std::size_t(u)] & ~fixed_[std::size_t(u)] & (kFixX | kFixY));
    // The walls' in node order (fixed_nodes_ is): a wall lists its nodes in the order it
    // took them, a restart in node order, and flip_slip's sum must not depend on which
    // of the two made the list.
    std::sort(flip_held_.begin() + long(walls_from), flip_held_.end(), [](const HeldStart& p, const HeldStart& q) { return p.node != q.node ? p.node < q.node : p.dirs < q.dirs; });
}

// Point k's second half of strain from b where it is now (with MAPPING SMOOTH's B-bar
// trace at the centroids of the sums just made), its stress and volume.
template <bool Trial> inline void Simulation::flip_second_strain(std::size_t k) {
    double dx, dy;
    StrainIncrement e = smooth_strain(overlap_[k], false, dx, dy);  // as smooth_move's
    e.xx *= 0.5; e.yy *= 0.5; e.xy *= 0.5; e.yx *= 0.5;
    smooth_stress<Trial>(k, e);
}

// 2: the transfer, then each point's second half of strain (flip_second_strain); then
// eq. 7 and 8 again, into the sums of `cells` (the box of every cell holding material).
inline void Simulation::flip_second_half(const Range& nodes, const Range& cells) {
    flip_transfer(nodes);
    centroid_traces(cells);
    each_point_consulted<false>([&](std::size_t k, auto trial) { flip_second_strain<decltype(trial)::value>(k); });
    // The first mapping's stress sums are zero (smear_points<Smear::Mass>), its masses those
    // of the points where they still are.
    zero_rows(cells, mx_, {&cvol_, &smu_, &smv_});
    Landing t;
    smear_points<Smear::Stress>(t);  // eq. 7, 8 where the points are
}

// 3: eq. 13-14 on M_n: each node's change a_n and its own increment b_n + a_n, which the
// supports then see as eq. 13's (impose_supports: fixed directions, walls).
inline void Simulation::flip_changes(const Range& nodes) {
    const double dt2 = sc_.dt_s * sc_.dt_s;
    for (int j = nodes.j0; j < nodes.j1; ++j)
        for (int i = nodes.i0; i < nodes.i1; ++i) {
            const std::size_t n = std::size_t(node(i, j));
            double ax = 0, ay = 0;
            const double M = flip_mass_[n];
            if (M > 0) {
                double cx, cy;
                if (!mean_ux_.empty()) { follow_mean(dux_[n], mean_beta_, mean_ux_[n]); follow_mean(duy_[n], mean_beta_, mean_uy_[n]); }  // DAMPING WINDOW
                damped_increment(dux_[n], fx_[n], M, dt2, sc_.damping, cx, mean_at(mean_ux_, n));  // eq. 13, 14
                damped_increment(duy_[n], fy_[n], M, dt2, sc_.damping, cy, mean_at(mean_uy_, n));
                ax = cx - dux_[n];  // a held direction's is replaced in flip_return
                ay = cy - duy_[n];
            } else if (!mean_ux_.empty()) {
                mean_ux_[n] = mean_uy_[n] = 0;  // DAMPING WINDOW: no mass, no mean motion
            }
            flip_ax_[n] = ax; flip_ay_[n] = ay;
            dux_[n] = M > 0 ? dux_[n] + ax : 0.0;
            duy_[n] = M > 0 ? duy_[n] + ay : 0.0;
        }
}

// Point k's change where it is, g = sum_n w_nk a_n.
inline void Simulation::flip_point_change(std::size_t k, double& gx, double& gy) const {
    double sx = 0, sy = 0;  // (not gx, gy: through a reference each term went to memory and back)
    flip_weights(k, [&](std::size_t n, double w) LPFDM_INLINE { sx += w * flip_ax_[n]; sy += w * flip_ay_[n]; });
    gx = sx; gy = sy;
}

// Point k takes its change (gx, gy): its increment d + g, its share of what the lattice
// gets back, sum_n w_nk m_k g; returns its kinetic energy's term m d(old) . d(new) / 2.
inline double Simulation::flip_point_return(std::size_t k, double gx, double gy) {
    const double m = groups_[p_.group[k]].mass, ux = p_.flip_ux[k], uy = p_.flip_uy[k];
    p_.flip_ux[k] = ux + gx; p_.flip_uy[k] = uy + gy;
    return 0.5 * m * (ux * (ux + gx) + uy * (uy + gy));
}

// 3, after the supports: a direction a support holds (fixed, or driven by a wall) takes
// the change that brings it to the support's increment, d - b_n; the points take the
// change where they are, d_p += g_p = sum_n w_np a_n; the lattice moves by what they will
// bring back, c_n = b_n + sum_p w_np m_p g_p / M_n, the held directions at the support's
// increment again; and the points' kinetic energy, summed in point order. The changes are
// found first, each point on its own (by threads in the fast kernel), and kept (flip_gx_).
inline void Simulation::flip_return(const Range& nodes) {
    const double dt2 = sc_.dt_s * sc_.dt_s;
    for (int j = nodes.j0; j < nodes.j1; ++j)
        for (int i = nodes.i0; i < nodes.i1; ++i) {
            const std::size_t n = std::size_t(node(i, j));
            const std::uint8_t held = std::uint8_t(fixed_[n] | driven_[n]);
            if ((held & kFixX) && flip_mass_[n] > 0) flip_ax_[n] = dux_[n] - dux_old_[n];
            if ((held & kFixY) && flip_mass_[n] > 0) flip_ay_[n] = duy_[n] - duy_old_[n];
        }
    flip_slip();
    double *gx = flip_gx_.data(), *gy = flip_gy_.data(), kinetic = 0;
    each_point([&](std::size_t k) { flip_point_change(k, gx[k], gy[k]); });
    flip_sums(nodes, gx, gy, flip_sx_.data(), flip_sy_.data(), nullptr);  // the points' shares of what the lattice gets back
    for (std::size_t k = 0; k < p_.size(); ++k) kinetic += flip_point_return(k, gx[k], gy[k]);
    flip_kinetic_ = kinetic / dt2;
    for (int j = nodes.j0; j < nodes.j1; ++j)
        for (int i = nodes.i0; i < nodes.i1; ++i) {
            const std::size_t n = std::size_t(node(i, j));
            const double M = flip_mass_[n];
            const std::uint8_t held = std::uint8_t(fixed_[n] | driven_[n]);
            if (!(held & kFixX)) dux_[n] = M > 0 ? dux_old_[n] + flip_sx_[n] / M : 0.0;  // a held direction keeps its support's
            if (!(held & kFixY)) duy_[n] = M > 0 ? duy_old_[n] + flip_sy_[n] / M : 0.0;
        }
}

// The slip at the supports in the step (the account's d_slip): a direction a support
// holds started from the support's increment b_s (flip_transfer), not from the points'
// there, b_p = sum_p w_np m_p d_p / M_n; its change a_n = d - b_s reaches the points,
// whose kinetic energy gains sum_n M_n a_n b_p / dt^2 (to first order), while the
// support's work counts its force on the node's increment, sum_n M_n a_n b_s / dt^2. The
// difference, sum_n M_n a_n (b_s - b_p) / dt^2, is the force on the slip between the
// support and the material beside it. Nonzero where a support changes speed: SHAKE's
// ground (the rigid base's shaken column: 1.7 % of the ground's work at 20 cells over H,
// 0.44 % at 40), a wall given a new velocity, an embedded wall's two lines of nodes (its
// increments there change as it crosses the cell) and a node a wall lets go; 0 for a fixed
// node and a wall at a steady speed on its line of nodes (a = 0), and for a node a wall
// takes for the first time (b_s = b_p). It can be negative (a wall stopped at once). It is
// first order in the change: an impact (a wall taking nodes, or stopped in one step) also
// loses (sum_n M_n a_n^2 - sum_p m_p g_p^2) / 2 dt^2 through the weights, which is not
// named (over SHAKE's small changes the lag it leaves is in the next step's b_p).
inline void Simulation::flip_slip() {
    double slip = 0;
    for (const HeldStart& h : flip_held_) {
        const std::size_t n = std::size_t(h.node);
        const double M = flip_mass_[n];
        if (M == 0) continue;
        if (h.dirs & kFixX) slip += M * flip_ax_[n] * (dux_old_[n] - h.bx);
        if (h.dirs & kFixY) slip += M * flip_ay_[n] * (duy_old_[n] - h.by);
    }
    es_.d_slip += slip / (sc_.dt_s * sc_.dt_s);
}

// ADVECT FLIP's step 5 (reference_integrate's and integrate's, for it) on the box `nodes`
// (flip_nodes), of which `now` holds the nodes with mass this step (the rest are cleared:
// the fast kernel's nodal_forces wrote `now` only): eq. 10 put gravity on m_n into F,
// and F is the force on the transfer's M_n (inertia); eq. 13, 14 on those masses
// (flip_changes), the supports, then the change back to the points (flip_return), whose
// kinetic energy is the account's. SHAKE and ABSORB as in reference_integrate, on the
// transfer's masses; the dashpots' change goes to the points as eq. 13's does.
// Returns the box of the nodes the walls drove.
inline Range Simulation::flip_integrate(const Range& nodes, const Range& now) {
    for (int j = nodes.j0; j < nodes.j1; ++j)
        for (int i = nodes.i0; i < nodes.i1; ++i) {
            const std::size_t n = std::size_t(node(i, j));
            if (i < now.i0 || i >= now.i1 || j < now.j0 || j >= now.j1) { nmass_[n] = fx_[n] = fy_[n] = 0; continue; }
            fx_[n] += sc_.gravity_x * (flip_mass_[n] - nmass_[n]);
            fy_[n] += sc_.gravity_y * (flip_mass_[n] - nmass_[n]);
        }
    if (modes_.dynamic) dynamics_begin();  // the ground's step, the boundary forces (SHAKE, ABSORB)
    keep_increments(nodes);  // for the energy account
    flip_changes(nodes);     // eq. 13, 14 on the transfer's masses
    integrated_ = nodes;
    if (modes_.dynamic) {  // the dashpots of ABSORB, and the change they make to the points
        absorb_increments();
        for (const std::int32_t u : absorb_nodes_) {
            const std::size_t n = std::size_t(u);
            if (flip_mass_[n] > 0) { flip_ax_[n] = dux_[n] - dux_old_[n]; flip_ay_[n] = duy_[n] - duy_old_[n]; }
        }
    }
    const Range walls = impose_supports();
    flip_return(nodes);  // the change to the points, and back
    if (modes_.dynamic) absorb_work();  // on the increments the points brought back
    for (int j = nodes.j0; j < nodes.j1; ++j) energy_row_terms(j, nodes.i0, nodes.i1, std::false_type{});
    const double peak = es_.peak_kinetic;
    if (!nodes.empty()) tally_energy(nodes.j0, nodes.j1);
    es_.kinetic = flip_kinetic_;  // the points' (flip_return)
    es_.peak_kinetic = std::max(peak, es_.kinetic);
    nodal_kinetic(nodes);
    return walls;
}

// ======================================================================================
// ADVECT POINTS
//
// Where the paper is open, the choices made here (each tested in tests/):
// * ADVECT POINTS (an option; eq. 12 stays the default) replaces eq. 12: each point
//   takes its eq. 7 increment and its cell's eq. 5 strain, an affine increment field,
//   and brings it with its mass to the four nodes of the cell it lands in (an affine
//   particle-in-cell transfer with eq. 10's quarter weights). A rigid rotation then
//   keeps its shape: a block turned through 90 degrees on 4 cells of L across keeps
//   its point distances to 0.08 % (eq. 12: 28 %). It needs MOTION CENTRE or BILINEAR:
//   carried from eq. 7a/7b about node [1], increments grew without bound. Linear
//   momentum is kept only up to sum m E r (r: a point's offset from its cell centre).
// ======================================================================================

inline void Simulation::carry_to(int c, int i, int j, double m, double x, double y, double dx, double dy, const StrainIncrement& e) {
    const double exx = e.xx, eyy = e.yy, exy = e.xy, eyx = e.yx;
    const double rx = x - (i + 0.5) * L_, ry = y - (j + 0.5) * L_;
    Carried& k = carried_[std::size_t(c)];
    k.px += m * (dx - exx * rx - exy * ry);
    k.py += m * (dy - eyx * rx - eyy * ry);
    k.qxx += m * exx; k.qxy += m * exy; k.qyx += m * eyx; k.qyy += m * eyy;
}

// ADVECT POINTS, in place of eq. 12: each node's increment is the mass-weighted mean of
// the increment fields the points brought to its (up to) four cells, each evaluated at
// the node, sum_c (P_c + Q_c r) / sum_c m_c with r the node's offset from the centre of
// cell c (an affine particle-in-cell transfer with eq. 10's quarter weights). An affine
// field (translation, rigid rotation, uniform strain) comes back as d(x_node) - E d_point:
// what eq. 12 gives to first order in E.
inline void Simulation::carried_increments(const Range& nr) {
    by_rows(kCarryRows, nr.j0, nr.j1, nr.size(), [&](int j) { carried_row(j, nr.i0, nr.i1); });
}
inline void Simulation::carried_row(int j, int i0, int i1) {
    const double h = 0.5 * L_;
    {
        for (int i = i0; i < i1; ++i) {
            double px = 0, py = 0, m = 0;
            const bool left = i > 0, right = i < mx_, below = j > 0, above = j < my_;
            auto add = [&](int ci, int cj, double rx, double ry) {
                const int c = cell(ci, cj);
                const Carried& k = carried_[std::size_t(c)];
                px += k.px + k.qxx * rx + k.qxy * ry;
                py += k.py + k.qyx * rx + k.qyy * ry;
                m += cmass_[c];
            };
            if (right && above) add(i, j, -h, -h);          // the node is corner [1] of cell (i, j)
            if (left && above) add(i - 1, j, h, -h);        // [2] of (i-1, j)
            if (right && below) add(i, j - 1, -h, h);       // [3] of (i, j-1)
            if (left && below) add(i - 1, j - 1, h, h);     // [4] of (i-1, j-1)
            const int n = node(i, j);
            if (m > 0) { dux_[n] = px / m; duy_[n] = py / m; }
        }
    }
}

// ======================================================================================
// HOURGLASS
//
// Eq. 5's one strain per cell does not see the checkerboard pattern (+1, -1, -1, +1) of
// nodal increments: nothing resists it. HOURGLASS kappa (off by default) adds the smallest
// remedy, a viscous force on that pattern alone: each cell's part of the pattern
// (checkerboard_mode, made with the strains) against its mass.
// ======================================================================================

// reference_nodal_forces' share of HOURGLASS at the node that is corner [1] of cell c:
// F[a] = -kappa (M_J / 4) q_J h[a] / dt^2 (khg = kappa / 4 dt^2).
LPFDM_INLINE inline void Simulation::hourglass_node_force(int c, bool right, bool left, bool above, bool below, double khg, double& fx, double& fy) const {
    auto hg = [&](int a, double h) {
        fx -= khg * cmass_[std::size_t(a)] * hgx_[std::size_t(a)] * h;
        fy -= khg * cmass_[std::size_t(a)] * hgy_[std::size_t(a)] * h;
    };
    if (right && above) hg(c, 1);
    if (left && above) hg(c - 1, -1);
    if (right && below) hg(c - mx_, -1);
    if (left && below) hg(c - mx_ - 1, 1);
}

#endif  // LPFDM_IMPLEMENTATION: from the lattice's members to ADVECT POINTS and HOURGLASS
// ======================================================================================
// EARTHQUAKES: SHAKE AND ABSORB
//
// Where the paper is open, the choices made here (each tested in tests/):
// * Earthquakes (SHAKE, ABSORB; not in the paper, FLAC's dynamic option): the ground's
//   velocity at each half step is the record's exact integral up to that time (linear
//   between samples), its increment that velocity times dt, as eq. 13 integrates a node;
//   the fixed nodes in a shaken direction take that increment. The lattice does not move
//   with the ground (its displacement should stay small against L). Dashpots -C v act on
//   the step's mean velocity (b + c) / 2 dt, solved for c (stable at any C): the explicit
//   form, -C b / dt, is unstable once C dt / m > 2, which an edge node of a cell barely
//   filled reaches at any dt; under a rigid SHAKE on the motion relative to the ground
//   (against the ground at rest they resisted a stiff layer moving with its base). A
//   compliant base's input is Joyner and Chen's traction
//   2 rho c v_in at the start of the step. At START an absorbing edge's fixed nodes are
//   released (but for a rigidly shaken direction) and keep their reaction as a constant
//   force (FLAC does the same). Local
//   damping acts on absolute velocities (as in FLAC), with SHAKE's DAMPING from START.
// ======================================================================================
namespace detail {
// The integral of a SHAKE record's acceleration over the record's times [ta, tb]: zero
// outside its samples, linear between them (each piece integrated exactly), SCALE
// applied, the trend c0 + c1 t taken off where the record is defined. `at` (a sample
// index) follows the times asked forward.
inline double record_integral(const Shake& k, double c0, double c1, std::size_t& at, double ta, double tb) {
    ta = std::max(ta, k.t.front());
    tb = std::min(tb, k.t.back());
    if (!(tb > ta)) return 0.0;
    while (at > 0 && k.t[at] > ta) --at;
    double sum = 0;
    for (std::size_t i = at; i + 1 < k.t.size() && k.t[i] < tb; ++i) {
        const double t0 = k.t[i], t1 = k.t[i + 1], a = std::max(ta, t0), b = std::min(tb, t1);
        if (t1 <= ta) { at = i + 1; continue; }  // wholly before the window: the next call starts after it
        if (!(b > a)) continue;
        auto value = [&](double t) { return k.a[i] + (t - t0) / (t1 - t0) * (k.a[i + 1] - k.a[i]); };
        sum += 0.5 * (b - a) * (value(a) + value(b));
    }
    return k.scale * sum - (c0 * (tb - ta) + c1 * 0.5 * (tb * tb - ta * ta));
}
// BASELINE's trend c0 + c1 t for time step dt: the record integrated step by step as the
// ground is (Simulation::ground_step), and the same for a = 1 and a = t where the record
// is defined; taking c0 + c1 t off makes the final velocity and displacement zero.
inline void baseline_trend(const Shake& k, double dt, double& c0, double& c1) {
    c0 = c1 = 0;
    double va = 0, da = 0, v1 = 0, d1 = 0, vt = 0, dtt = 0;
    std::size_t at = 0;
    for (long n = 0;; ++n) {
        const double ta = (double(n) - 0.5) * dt, tb = (double(n) + 0.5) * dt;
        if (ta > k.t.back()) break;
        const double a = std::max(ta, k.t.front()), b = std::min(tb, k.t.back());
        va += record_integral(k, 0, 0, at, ta, tb); da += va * dt;
        v1 += b > a ? b - a : 0.0; d1 += v1 * dt;
        vt += b > a ? 0.5 * (b * b - a * a) : 0.0; dtt += vt * dt;
    }
    const double det = v1 * dtt - vt * d1;
    if (det != 0) { c0 = (va * dtt - vt * da) / det; c1 = (v1 * da - va * d1) / det; }
}
// The first step of a SHAKE card's motion: START / dt rounded up (validate refuses START
// beyond 1e15 steps; the bound keeps the conversion defined for a scene built in code).
inline long start_step(const Shake& k, double dt) { return long(std::min(std::ceil(k.start / dt - 1e-9), 1e18)); }

inline void GroundMotion::step(long n, double dt) {
    const double tau = double(n - first) * dt, v0 = v;
    v += record_integral(*spec, c0, c1, at, tau - 0.5 * dt, tau + 0.5 * dt);
    du_before = du;
    du = v * dt;
    d += du;
    v_now = 0.5 * (v0 + v);
}
// The largest ground displacement a rigid SHAKE gives in a run of `steps` steps of dt
// (after the record, the ground keeps the velocity it ended with). For a warning only:
// over a record of more than 1e6 steps the steps are made longer (at most 1e6 of them),
// so that the check stays quick whatever the deck.
inline double ground_excursion(const Shake& k, double dt, long steps) {
    const double h = std::max(dt, (k.start + k.t.back()) / 1e6);
    steps = long(std::min(double(steps), std::ceil(double(steps) * dt / h)));
    GroundMotion g;
    g.spec = &k;
    g.first = start_step(k, h);
    if (k.baseline) baseline_trend(k, h, g.c0, g.c1);
    double most = 0;
    long n = g.first;
    for (; n < steps && double(n - g.first) * h - 0.5 * h <= k.t.back(); ++n) {
        g.step(n, h);
        most = std::max(most, std::fabs(g.d));
    }
    return std::max(most, std::fabs(g.d + g.v * h * double(std::max(0L, steps - n))));
}
}  // namespace detail
#if defined(LPFDM_IMPLEMENTATION)  // out-of-line definitions (left out by LPFDM_INTERNALS alone)

// What is wrong with a SHAKE card's record (an empty string if nothing): at least two
// samples, finite, times from 0 on and increasing.
LPFDM_DEF std::string record_problem(const Shake& k) {
    if (k.t.size() != k.a.size()) return "has " + std::to_string(k.t.size()) + " times and " + std::to_string(k.a.size()) + " accelerations";
    if (k.t.size() < 2) return "needs at least two samples (it has " + std::to_string(k.t.size()) + ")";
    for (std::size_t i = 0; i < k.t.size(); ++i) {
        if (!std::isfinite(k.t[i]) || !std::isfinite(k.a[i])) return "holds a value that is not a finite number (sample " + std::to_string(i + 1) + ")";
        if (k.t[i] < 0) return "starts before time 0 (sample " + std::to_string(i + 1) + ")";
        if (i > 0 && !(k.t[i] > k.t[i - 1])) return "does not increase in time (sample " + std::to_string(i + 1) + ")";
    }
    return "";
}

// ------------------------------------------------ earthquakes: SHAKE, ABSORB ---
// The ground's motion in step n, each shaken direction (detail::GroundMotion::step).
inline void Simulation::ground_step(long n) {
    for (Ground& g : ground_)
        if (g.spec) g.step(n, sc_.dt_s);
}

// After a restart: the ground's motion up to the step read (the same operations as the
// run made, so the same numbers), and the edges released at START released again (their
// reactions come from the state file).
inline void Simulation::replay_ground() {
    for (Ground& g : ground_) g.rewind();
    for (long n = 0; n < step_; ++n) ground_step(n);
    if (step_ > shake_step_)
        for (std::size_t q = 0; q < absorb_nodes_.size(); ++q) fixed_[std::size_t(absorb_nodes_[q])] &= std::uint8_t(~released_[q]);
}

// Ground motion and absorbing edges, made at set-up: which card shakes which direction,
// BASELINE's trend, and the dashpots of each absorbing edge (ABSORB, and the bottom edge
// of a COMPLIANT shake). A dashpot's impedances rho c_p and rho c_s are those of the
// material the points of its edge cell were made of (of the nearest such cell along the
// edge, for a cell made empty): it acts while that cell holds mass.
inline void Simulation::setup_dynamics() {
    if (!modes_.dynamic) return;
    const double dt = sc_.dt_s;
    int edges = sc_.absorb;
    for (const Shake& k : sc_.shakes) {
        Ground& g = ground_[k.dir == kFixX ? 0 : 1];
        g.spec = &k;
        if (k.compliant) edges |= kBottom;
        shake_step_ = g.first = detail::start_step(k, dt);
        if (k.baseline) detail::baseline_trend(k, dt, g.c0, g.c1);
    }
    // The material each edge cell's points were made of (of two, the later cluster's).
    std::vector<const Material*> made_of;  // per cell, for the edges that absorb
    if (edges) {
        made_of.assign(std::size_t(mx_) * my_, nullptr);
        detail::made_points(sc_.clusters, L_, mx_, my_, [&](int i, int j, int k, int, int) {
            made_of[std::size_t(cell(i, j))] = sc_.material(sc_.clusters[std::size_t(k)].mat);
        });
    }
    auto material_of = [&](int i, int j) { return made_of[std::size_t(cell(i, j))]; };
    std::vector<std::int32_t> slot_of(std::size_t(mx_ + 1) * (my_ + 1), -1);
    // Edge e: its cells (i, j) = start + k step, k < count, and each cell's two nodes on the edge.
    struct Edge { int bit, i, j, di, dj, count; bool horizontal; };
    const Edge all[] = {{kBottom, 0, 0, 1, 0, mx_, true}, {kTop, 0, my_ - 1, 1, 0, mx_, true},
                        {kLeft, 0, 0, 0, 1, my_, false}, {kRight, mx_ - 1, 0, 0, 1, my_, false}};
    for (const Edge& e : all) {
        if (!(edges & e.bit)) continue;
        std::vector<const Material*> mats(std::size_t(e.count));
        for (int k = 0; k < e.count; ++k) mats[std::size_t(k)] = material_of(e.i + k * e.di, e.j + k * e.dj);
        for (int k = 0; k < e.count; ++k) {
            const Material* m = mats[std::size_t(k)];
            for (int r = 1; !m && r < e.count; ++r) {  // the nearest cell along the edge that had material
                if (k - r >= 0 && mats[std::size_t(k - r)]) m = mats[std::size_t(k - r)];
                else if (k + r < e.count && mats[std::size_t(k + r)]) m = mats[std::size_t(k + r)];
            }
            if (!m) continue;
            const double zp = m->rho * m->p_wave_speed() * 0.5 * L_, zs = m->rho * std::sqrt(m->shear() / m->rho) * 0.5 * L_;
            const int ci = e.i + k * e.di, cj = e.j + k * e.dj;
            const double cx = e.horizontal ? zs : zp, cy = e.horizontal ? zp : zs;
            const bool in_x = e.bit == kBottom && ground_[0].spec && ground_[0].spec->compliant;
            const bool in_y = e.bit == kBottom && ground_[1].spec && ground_[1].spec->compliant;
            for (int side = 0; side < 2; ++side) {
                const int ni = e.horizontal ? ci + side : (e.bit == kLeft ? 0 : mx_);
                const int nj = e.horizontal ? (e.bit == kBottom ? 0 : my_) : cj + side;
                const std::size_t n = std::size_t(node(ni, nj));
                if (slot_of[n] < 0) {
                    slot_of[n] = std::int32_t(absorb_nodes_.size());
                    absorb_nodes_.push_back(std::int32_t(n));
                    // A node gives up its FIX at SHAKE's START if every lattice edge it lies on
                    // absorbs (a corner of a rigid base stays with the base); without SHAKE
                    // there is no moment to take its reaction at rest, and it stays fixed.
                    const int on = (nj == 0 ? kBottom : 0) | (nj == my_ ? kTop : 0) | (ni == 0 ? kLeft : 0) | (ni == mx_ ? kRight : 0);
                    // A direction a rigid SHAKE drives stays with the ground.
                    released_.push_back((on & ~edges) || !modes_.shake ? std::uint8_t(0) : std::uint8_t(fixed_[n] & ~shaken_dirs()));
                }
                dashpots_.push_back({slot_of[n], cell(ci, cj), cx, cy, in_x ? 2 * cx : 0.0, in_y ? 2 * cy : 0.0});
            }
        }
    }
    for (auto* v : {&absorb_cx_, &absorb_cy_, &input_fx_, &input_fy_, &hold_fx_, &hold_fy_, &dashpot_fx_, &dashpot_fy_}) v->assign(absorb_nodes_.size(), 0.0);
}

// The start of eq. 13's phase in a scene that shakes or absorbs (both kernels): the
// ground's step; from START on the deck's damping gives way to SHAKE's DAMPING, the
// absorbing edges' nodes give up their FIX (each keeps the reaction it had then as a
// constant force: the static load stays, its motion is free) and the dashpots act. The
// nodal forces get those reactions and a compliant base's input traction 2 rho c v_in.
inline void Simulation::dynamics_begin() {
    ground_step(step_);
    if (step_ < shake_step_) return;
    if (modes_.shake && sc_.shakes.front().damping >= 0) sc_.damping = sc_.shakes.front().damping;  // the cards agree (validate)
    const bool release = step_ == shake_step_;
    const double vx = ground_[0].v_now, vy = ground_[1].v_now;
    for (std::size_t q = 0; q < absorb_nodes_.size(); ++q) {
        const std::size_t n = std::size_t(absorb_nodes_[q]);
        if (release && released_[q]) {  // the force the support exerted: it cancelled F
            if (released_[q] & kFixX) hold_fx_[q] = -fx_[n];
            if (released_[q] & kFixY) hold_fy_[q] = -fy_[n];
            fixed_[n] &= std::uint8_t(~released_[q]);
        }
        absorb_cx_[q] = absorb_cy_[q] = input_fx_[q] = input_fy_[q] = 0;
    }
    for (const Dashpot& d : dashpots_) {
        if (cmass_[std::size_t(d.cell)] == 0) continue;
        const std::size_t q = std::size_t(d.slot);
        absorb_cx_[q] += d.cx; absorb_cy_[q] += d.cy;
        input_fx_[q] += d.ix * vx; input_fy_[q] += d.iy * vy;
    }
    for (std::size_t q = 0; q < absorb_nodes_.size(); ++q) {
        const std::size_t n = std::size_t(absorb_nodes_[q]);
        if (inertia()[n] == 0) continue;
        fx_[n] += hold_fx_[q] + input_fx_[q];
        fy_[n] += hold_fy_[q] + input_fy_[q];
    }
}

// The dashpots of the absorbing edges, after eq. 13-14 gave a node the increment c0 from b:
// a force -C (v - v_g) with v the step's mean velocity (b + c) / 2 dt and v_g the ground's
// (b_g + c_g) / 2 dt where a rigid SHAKE moves it in that direction (the far field moves
// with the base: a side dashpot against the ground at rest held the shaken layer back by a
// third), else 0; taken implicitly (stable at any C): c (1 + beta) = c0 - beta (b - b_g -
// c_g), beta = C dt / 2m. Fixed directions are left to impose_supports (a wall on an
// absorbing edge is refused: validate). Each force is kept for absorb_work.
inline void Simulation::absorb_increments() {
    if (step_ < shake_step_) return;
    const double dt = sc_.dt_s;
    auto one = [&](std::size_t n, const Ground& g, double C, double b, double& c, double& f) {
        const bool rigid = g.rigid();
        const double bg = rigid ? g.du_before : 0.0, cg = rigid ? g.du : 0.0, beta = C * dt / (2 * inertia()[n]);
        c = (c - beta * (b - bg - cg)) / (1 + beta);
        f = -C * ((b + c) - (bg + cg)) / (2 * dt);  // the dashpot's force on the node
    };
    for (std::size_t q = 0; q < absorb_nodes_.size(); ++q) {
        const std::size_t n = std::size_t(absorb_nodes_[q]);
        if (inertia()[n] == 0) continue;
        const std::uint8_t held = fixed_[n];
        if (!(held & kFixX)) one(n, ground_[0], absorb_cx_[q], dux_old_[n], dux_[n], dashpot_fx_[q]);
        if (!(held & kFixY)) one(n, ground_[1], absorb_cy_[q], duy_old_[n], duy_[n], dashpot_fy_[q]);
    }
    if (modes_.advect != Advect::Flip) absorb_work();
}

// The energy account's terms of the absorbing edges in the step: the dashpots'
// dissipation, the ground's work through them, the input traction's and the held
// reactions' work (each with its trapezoidal half step, as support_work), every force on
// the node's increment from b to c as the step leaves it: with ADVECT FLIP after
// flip_return, whose c_n is what the points bring back (the increment their strain
// follows), not eq. 13's and the dashpots' c0. (On the dashpots' c0 the account of a
// compliant base under FLIP read 0.63 % of the ground's work made, and 0.13 % at L / 2.)
inline void Simulation::absorb_work() {
    if (step_ < shake_step_) return;
    double ha = 0, hi = 0, hh = 0;
    auto one = [&](const Ground& g, double f, double fin, double hold, double b, double c) {
        const bool rigid = g.rigid();
        const double bg = rigid ? g.du_before : 0.0, cg = rigid ? g.du : 0.0;
        const double s = b + c, sg = bg + cg;
        es_.d_absorb -= 0.5 * f * (s - sg); ha -= 0.5 * f * (c - cg);
        es_.w_ground += 0.5 * f * sg + 0.5 * fin * s; hi += 0.5 * f * cg + 0.5 * fin * c;
        es_.w_held += 0.5 * hold * s; hh += 0.5 * hold * c;
    };
    for (std::size_t q = 0; q < absorb_nodes_.size(); ++q) {
        const std::size_t n = std::size_t(absorb_nodes_[q]);
        if (inertia()[n] == 0) continue;
        const std::uint8_t held = fixed_[n];
        if (!(held & kFixX)) one(ground_[0], dashpot_fx_[q], input_fx_[q], hold_fx_[q], dux_old_[n], dux_[n]);
        if (!(held & kFixY)) one(ground_[1], dashpot_fy_[q], input_fy_[q], hold_fy_[q], duy_old_[n], duy_[n]);
    }
    es_.h_absorb = ha; es_.h_input = hi; es_.h_held = hh;
}

#endif  // LPFDM_IMPLEMENTATION: the earthquakes' members of Simulation
// ======================================================================================
// THE FAST KERNEL
//
// The same cycle as the reference, over the occupied part of the lattice only, by threads
// (OpenMP) and four values per AVX2 register; every function here equals the reference
// function it names, bit for bit (tests/test_reference.cpp).
//
// Loops over points, cells and node rows run in parallel when compiled with OpenMP
// (-fopenmp). Every sum that reaches a result is taken in one fixed order, so the
// output is the same, byte for byte, with any number of threads: the cell sums of eq. 7
// and 8 take their terms in point order (a thread's points that land in another
// thread's cells are added afterwards, in order), node sums in row order.
// The points are stored cell by cell (as created, and sorted so again every REORDER
// steps; between sorts they leave that order as they cross cell edges), so the point
// phase of an elastic scene walks runs of points sharing a cell and reads the cell's
// strain, rotation and nodes once per run; a scene with a Mohr-Coulomb material takes
// the points four at a time whatever cells they lie in (a flow's runs are one or two
// points long), reading those values once where the four share a cell. A sort changes
// the last bits of a run (the next step's sum in a cell takes the points arriving from
// its neighbours in another order), not its bytes from one kernel or thread count to
// another.
// ======================================================================================
namespace detail {

#if LPFDM_WIDE
// eq. 7, 8 (CellSums::add) for four points of one group, of volume vol and stress (sxx,
// syy, sxy) in the lanes, into acc = (sum V, sum V sxx, sum V syy, sum V sxy): each
// point's terms made in lanes (V = min(vol, vol0)), turned into one register per point
// and added in point order, so that every component takes its terms in the order the
// one-point code does.
LPFDM_INLINE inline void add_four(v4d& acc, const v4d& vol, const v4d& sxx, const v4d& syy, const v4d& sxy, double vol0) {
    const v4d v0 = {vol0, vol0, vol0, vol0};
    const v4d vk = v0 < vol ? v0 : vol;  // std::min(vol, vol0)
    const v4d vx = vk * sxx, vy = vk * syy, vxy = vk * sxy;
    const v4d t0 = LPFDM_SHUFFLE(vk, vx, 0, 4, 2, 6), t1 = LPFDM_SHUFFLE(vk, vx, 1, 5, 3, 7);  // points 0 2, 1 3
    const v4d t2 = LPFDM_SHUFFLE(vy, vxy, 0, 4, 2, 6), t3 = LPFDM_SHUFFLE(vy, vxy, 1, 5, 3, 7);
    acc += LPFDM_SHUFFLE(t0, t2, 0, 1, 4, 5);  // point 0
    acc += LPFDM_SHUFFLE(t1, t3, 0, 1, 4, 5);  // point 1
    acc += LPFDM_SHUFFLE(t0, t2, 2, 3, 6, 7);  // point 2
    acc += LPFDM_SHUFFLE(t1, t3, 2, 3, 6, 7);  // point 3
}
namespace lanes {
// eq. 6's elastic test and plastic return of N elastic trials at once, in the lanes of a
// vector V of N doubles (M: its mask, all ones or zero in a lane): mohr_inside and
// mohr_coulomb_correct's closed-form shear return and the first two sets of its search,
// with the same operations in the same order as those compute them one stress at a time
// (std::min(a, b) is b < a ? b : a, std::max(a, b) a < b ? b : a), so the lanes they settle
// get the same numbers bit for bit. Four lanes: AVX2 registers. Every function here and
// every lambda is built for AVX2 (LPFDM_LANE): a compiler lowers the vector code of a
// function built for less, lane by lane.
using V = v4d;
using M = v4m;
#define LPFDM_LANE __attribute__((always_inline, target("avx2")))
constexpr int N = 4;
// bit l of lane l, and byte l of a word of N bytes (all ones) in lane l
constexpr M kLaneBit = {1, 2, 4, 8}, kLaneByte = {0xff, 0xff00, 0xff0000, 0xff000000};
// bit l: lane l's sign bit (of a mask: lane l set)
LPFDM_LANE inline int bits(const M& m) {
    return __builtin_ia32_movmskpd256(v4d(m));
}
// r = sqrt(x) in each lane (correctly rounded, as std::sqrt)
LPFDM_LANE inline void sqrt_of(const V& x, V& r) {
    r = __builtin_ia32_sqrtpd256(x);
}
// m: lane l set where bit l of `b` is (bits' inverse)
LPFDM_LANE inline void lane_mask(int b, M& m) { m = M(((M{} + b) & kLaneBit) != 0); }
// a = |v| lane by lane (the sign bit cleared, as std::fabs does)
LPFDM_LANE inline void abs_of(const V& v, V& a) { a = V(M(v) & 0x7fffffffffffffffLL); }
// v = x in every lane (a broadcast: the same bits, the sign of a zero too)
LPFDM_LANE inline void splat(double x, V& v) {
    v = V{x, x, x, x};
}

// Mohr's circle of (xx, yy) with its radius r given: t.a, t.sig and mohr_inside's lo, hi
// and shear test.
LPFDM_LANE inline void circle(const V& xx, const V& yy, const V& zz, const V& r, const V& np, const V& two_c_sq, V& a, V& t0, V& t1, V& hi, M& shear_ok) {
    const V p = 0.5 * (xx + yy);
    a = 0.5 * (xx - yy);
    t0 = p - r; t1 = p + r;
    const V lo = zz < t0 ? zz : t0;
    hi = t1 < zz ? zz : t1;
    shear_ok = lo - hi * np + two_c_sq >= 0;
}
// mohr_inside's first exit: bit l set when trial l is inside with no tensile principal
// value. r: the circle's radius, for shear_return.
LPFDM_LANE inline int inside(const V& xx, const V& yy, const V& xy, const V& zz, const V& np, const V& two_c_sq, V& r) {
    constexpr double huge = std::numeric_limits<double>::infinity();
    V inf;
    splat(huge, inf);
    const V half_diff = 0.5 * (xx - yy);
    sqrt_of(V(half_diff * half_diff + xy * xy), r);
    V a, t0, t1, hi;
    M shear_ok;
    circle(xx, yy, zz, r, np, two_c_sq, a, t0, t1, hi, shear_ok);
    return bits(M(shear_ok & (hi <= 0) & (two_c_sq >= 0) & (np < inf)));
}
// std::min(std::min(a, b), c) and std::max(std::max(a, b), c) in each lane, with their
// operations (std::min(a, b) is b < a ? b : a, std::max(a, b) a < b ? b : a).
LPFDM_LANE inline void extremes(const V& a, const V& b, const V& c, V& lo, V& hi) {
    const V m = b < a ? b : a, big = a < b ? b : a;
    lo = c < m ? c : m;
    hi = big < c ? c : big;
}
// What shear_return found of each trial, for edge_return (mohr_coulomb_correct's
// names): the circle's a, the principal values t0 <= t1 and t2 = sig_zz, the tension limit,
// the tolerance, the tension plane's f at the largest, the order (A: t1 <= t2, C: t2 < t0,
// else t0 <= t2 < t1) and FLAC's choice of shear.
struct Found { V a, t0, t1, t2, sig_t, tol, ft; M A, C, shear_first; };
// The rest of mohr_inside (the tension planes) and the closed-form shear return of
// mohr_coulomb_correct (where FLAC's h chooses shear). Bit l of the result: lane l is
// settled; bit N + l (N lanes): it was returned by shear (its stress replaced, d_gamma[l]
// its plastic shear increment). A lane left unsettled (tension, an edge, or a return the closed form
// cannot make admissible) goes to edge_return (with `found`), and what that leaves to the
// one-point code. n_psi, tension, a1, a2: the material's (MaterialConstants).
LPFDM_LANE inline int shear_return(V& xx, V& yy, V& xy, V& zz, const V& r, const V& np, const V& two_c_sq, double n_psi, double tension, double a1, double a2, V& d_gamma, Found& found) {
    constexpr double huge = std::numeric_limits<double>::infinity();
    V inf, zero, one, n_psi_v, tension_v;
    splat(huge, inf); splat(0.0, zero); splat(1.0, one); splat(n_psi, n_psi_v); splat(tension, tension_v);
    V a, t0, t1, hi;
    M shear_ok;
    circle(xx, yy, zz, r, np, two_c_sq, a, t0, t1, hi, shear_ok);
    const V t2 = zz;
    V sig_t = np > 1 ? two_c_sq / (np - 1) : inf;  // tension_limit
    if (tension >= 0) sig_t = tension < sig_t ? tension_v : sig_t;
    const M inside = shear_ok & (sig_t - hi >= 0);  // implied by the first exit
    // The order of t0 <= t1 and t2 (t0 <= t1 holds for every lane without NaN, and a lane
    // with NaN in its trial or strength fails the check below through tol).
    const M above = t1 > t2, below = t0 > t2;
    const M A = ~above, B = above & ~below, C = above & below;  // (i1 i2 i3) = (0 1 2), (0 2 1), (2 0 1)
    const V ti1 = C ? t2 : t0, ti3 = A ? t2 : t1;
    const V fs = ti1 - ti3 * np + two_c_sq, ft = sig_t - ti3;
    V a0, a1v, a2v, at;
    abs_of(t0, a0); abs_of(t1, a1v); abs_of(t2, a2v); abs_of(sig_t, at);
    const V tol = 1e-11 * (a0 + a1v + a2v + two_c_sq + (at < inf ? sig_t : zero));
    const V ns0 = np < n_psi ? np : n_psi_v;  // std::min(n_psi, np)
    const V d1 = a1 - a2 * ns0, d2 = a2 * (1 - ns0), d3 = a2 - a1 * ns0;
    const V mu = -fs / (d1 - np * d3);
    const V s0 = t0 + mu * (C ? d2 : d1), s1 = t1 + mu * (A ? d2 : d3), s2 = t2 + mu * (A ? d3 : B ? d2 : d1);
    V lo_n, hi_n;
    extremes(s0, s1, s2, lo_n, hi_n);
    // FLAC's h chooses shear where the tension plane is violated too (h_fn, the same
    // operations; a lane with ft >= 0 does not need it, as the one-point code skips it, and
    // most groups hold no lane that does: their square root is not taken).
    M shear_first = (fs < 0) & (ft >= 0);
    if (const M both = (fs < 0) & ~(ft >= 0); bits(both)) {
        V root;
        sqrt_of(V(1 + np * np), root);
        const V alpha_p = root + np, sig_p = sig_t * np - two_c_sq;
        const V h = ti3 - sig_t + alpha_p * (ti1 - sig_p);
        shear_first |= both & ~(h > 0);
    }
    const M shear = ~inside & shear_first & (lo_n - np * hi_n + two_c_sq >= -tol) & (sig_t - hi_n >= -tol);
    // to_xy: the same principal direction, the new principal values
    const V pn = 0.5 * (s1 + s0), rn = 0.5 * (s1 - s0);
    const V inv_r = one / r, c2 = r > 0 ? a * inv_r : one, s2xy = r > 0 ? xy * inv_r : zero;
    xx = shear ? pn + rn * c2 : xx;
    yy = shear ? pn - rn * c2 : yy;
    xy = shear ? rn * s2xy : xy;
    zz = shear ? s2 : zz;
    abs_of(-mu - mu * ns0, d_gamma);  // |e1 - e3|
    found = Found{a, t0, t1, t2, sig_t, tol, ft, A, C, shear_first};
    return bits(M(inside | shear)) | bits(shear) << N;
}
// The lanes shear_return left (bits of `left`; their trials in xx .. zz, what it found of
// them in m): the first two
// sets of mohr_coulomb_correct's search, with the same operations in the same order, in
// lanes. Its closed-form shear return was not admissible there, or FLAC's h chose
// tension, whose return is made here and, where admissible, left to the one-point code.
// The search then pairs its plane p0 with first[0], then first[1], the pairs that end most
// searches in a flowing collapse (an edge of two shear planes, the apex line of shear and
// tension, the corner of tension and shear). Bit l of the result: lane l was returned by
// one of them (xx .. zz its stress, d_gamma[l] its plastic shear, as the one-point code's
// mode Edge gives them); a lane left unsettled (a third set, an infinite or NaN value, an
// admissible tension return) takes the one-point code, which tries the same two sets first.
LPFDM_LANE inline int edge_return(V& xx, V& yy, V& xy, V& zz, const V& r, const V& np, const V& two_c_sq, double n_psi, double a1, double a2, const Found& m, int left, V& d_gamma) {
    constexpr double huge = std::numeric_limits<double>::infinity();
    V inf, zero, one, two, n_psi_v;
    splat(huge, inf); splat(0.0, zero); splat(1.0, one); splat(2.0, two); splat(n_psi, n_psi_v);
    const V &a = m.a, &t0 = m.t0, &t1 = m.t1, &t2 = m.t2, &sig_t = m.sig_t, &tol = m.tol, &ft = m.ft;
    const M &C = m.C, &shear_first = m.shear_first;
    V a0, a1v, a2v, at, ar, anp, ac;
    abs_of(t0, a0); abs_of(t1, a1v); abs_of(t2, a2v); abs_of(sig_t, at); abs_of(r, ar); abs_of(np, anp); abs_of(two_c_sq, ac);
    // Finite values only (then nine planes, and t0 <= t1): any other lane takes the one-point code.
    const M finite = (a0 < inf) & (a1v < inf) & (a2v < inf) & (at < inf) & (ar < inf) & (anp < inf) & (ac < inf);
    M lanes;
    lane_mask(left, lanes);
    M todo = lanes & finite;
    if (!bits(todo)) return 0;
    // i1, i2, i3: the order of the trial's principal values, as mohr_coulomb_correct sorts them
    // ((0 1 2) in A, (2 0 1) in C, else (0 2 1)); the finite lanes' tol is the one-point code's
    const V i1 = C ? two : zero, i2 = m.A ? one : (C ? zero : two), i3 = m.A ? two : one;
    const V ns = np < n_psi ? np : n_psi_v;  // st.n_psi
    {  // the tension return of the closed form, where FLAC's h chose it: admissible lanes are the one-point code's
        const V mu = -ft / a1;
        const V d_other = mu * a2, d_i3 = mu * a1;  // sg[i1] -= mu a2, sg[i2] -= mu a2, sg[i3] -= mu a1
        const V g0 = t0 - (i3 == zero ? d_i3 : d_other), g1 = t1 - (i3 == one ? d_i3 : d_other), g2 = t2 - (i3 == two ? d_i3 : d_other);
        V lo, hi_t;
        extremes(g0, g1, g2, lo, hi_t);
        const M admissible = (lo - np * hi_t + two_c_sq >= -tol) & (sig_t - hi_t >= -tol);
        todo &= shear_first | ~admissible;
    }
    // A plane of the nine, lane by lane: shear (i, j), n = e_i - N_phi e_j and m = e_i - N_psi e_j,
    // or tension on i, n = m = -e_i; idx its number in mohr_coulomb_correct (2 i + (j > i ? j - 1 : j), 6 + i).
    struct Plane { V n[3], m[3], kk, idx; };
    const V n_one = 1.0 - np * 0.0, n_neg = 0.0 - np * 1.0, n_zero = 0.0 - np * 0.0;
    const V m_one = 1.0 - ns * 0.0, m_neg = 0.0 - ns * 1.0, m_zero = 0.0 - ns * 0.0;
    V minus_zero;
    splat(-0.0, minus_zero);
    const V minus_one = -one;
    auto shear_plane = [&](const V& i, const V& j, Plane& q) LPFDM_LANE {
        for (int t = 0; t < 3; ++t) {
            V tt;
            splat(double(t), tt);
            q.n[t] = i == tt ? n_one : (j == tt ? n_neg : n_zero);
            q.m[t] = i == tt ? m_one : (j == tt ? m_neg : m_zero);
        }
        q.kk = two_c_sq;
        q.idx = 2 * i + (j > i ? j - 1 : j);
    };
    auto tension_plane = [&](const V& i, Plane& q) LPFDM_LANE {
        for (int t = 0; t < 3; ++t) {
            V tt;
            splat(double(t), tt);
            q.n[t] = q.m[t] = i == tt ? minus_one : minus_zero;
        }
        q.kk = sig_t;
        q.idx = 6 + i;
    };
    auto pick = [](const M& c, const Plane& x, const Plane& y, Plane& q) LPFDM_LANE {
        for (int t = 0; t < 3; ++t) { q.n[t] = c ? x.n[t] : y.n[t]; q.m[t] = c ? x.m[t] : y.m[t]; }
        q.kk = c ? x.kk : y.kk;
        q.idx = c ? x.idx : y.idx;
    };
    // p0 and first[0], first[1] (mohr_coulomb_correct's order)
    const V o = i3 == two ? i1 : 1 - i3;
    Plane p0, q1, q2, x, y;
    shear_plane(i1, i3, x); tension_plane(i3, y); pick(shear_first, x, y, p0);
    shear_plane(i1, i2, x); shear_plane(o, i3, y); pick(shear_first, x, y, q1);
    tension_plane(i1, x); shear_plane(i3, o, y); pick(shear_first, x, y, q2);
    const double d12 = a1 - a2;
    const V mu_min = -tol / (a1 + 1);
    const V tr[3] = {t0, t1, t2};
    // try_set of the pair (p0, q), its planes in index order: true in the lanes where it is admissible
    auto try_pair = [&](const Plane& q, V sg[3], V& gamma, M& ok) LPFDM_LANE {
        const M p_first = p0.idx < q.idx;
        Plane u, v;
        pick(p_first, p0, q, u); pick(p_first, q, p0, v);
        V dm[2][3], f[2];
        const Plane* pl[2] = {&u, &v};
        for (int w = 0; w < 2; ++w) {
            const Plane& z = *pl[w];
            const V a2_tr = a2 * (z.m[0] + z.m[1] + z.m[2]);
            for (int t = 0; t < 3; ++t) dm[w][t] = a2_tr + d12 * z.m[t];
            f[w] = z.n[0] * tr[0] + z.n[1] * tr[1] + z.n[2] * tr[2] + z.kk;
        }
        V A[2][2];
        for (int w = 0; w < 2; ++w)
            for (int x = 0; x < 2; ++x) A[w][x] = pl[w]->n[0] * dm[x][0] + pl[w]->n[1] * dm[x][1] + pl[w]->n[2] * dm[x][2];
        const V b0 = -f[0], b1 = -f[1];
        // Gaussian elimination with partial pivoting, 2 x 2, as try_set
        V abs00, abs10;
        abs_of(A[0][0], abs00); abs_of(A[1][0], abs10);
        const M sw = abs10 > abs00;
        const V p00 = sw ? A[1][0] : A[0][0], p01 = sw ? A[1][1] : A[0][1], q10 = sw ? A[0][0] : A[1][0], q11 = sw ? A[0][1] : A[1][1];
        const V pb = sw ? b1 : b0, qb = sw ? b0 : b1;
        const V fr = q10 / p00;
        const V a11 = q11 - fr * p01, bb1 = qb - fr * pb;
        const V mu1 = bb1 / a11, mu0 = (pb - p01 * mu1) / p00;
        V ap00, aa11;
        abs_of(p00, ap00); abs_of(a11, aa11);
        V tiny;
        splat(1e-300, tiny);
        ok = ~(ap00 < tiny) & ~(aa11 < tiny) & ~(mu0 < mu_min) & ~(mu1 < mu_min);
        for (int t = 0; t < 3; ++t) { sg[t] = tr[t]; sg[t] += mu0 * dm[0][t]; sg[t] += mu1 * dm[1][t]; }
        V lo, hi_n;
        extremes(sg[0], sg[1], sg[2], lo, hi_n);
        ok &= ~(lo - np * hi_n + two_c_sq < -tol) & ~(sig_t - hi_n < -tol);
        // plastic strains d_eps^p = -sum mu_a m_a; d_gamma = max - min
        V ep[3];
        for (int t = 0; t < 3; ++t) { ep[t] = zero; ep[t] -= mu0 * u.m[t]; ep[t] -= mu1 * v.m[t]; }
        V e_min, e_max;
        extremes(ep[0], ep[1], ep[2], e_min, e_max);
        gamma = e_max - e_min;
    };
    V sg[3], best[3], gamma, best_gamma;
    M done, second;
    try_pair(q1, sg, gamma, done);
    done &= todo;
    for (int t = 0; t < 3; ++t) best[t] = sg[t];
    best_gamma = gamma;
    if (bits(M(todo & ~done))) {
        try_pair(q2, sg, gamma, second);
        second &= todo & ~done;
        for (int t = 0; t < 3; ++t) best[t] = second ? sg[t] : best[t];
        best_gamma = second ? gamma : best_gamma;
        done |= second;
    }
    // to_xy: the same principal direction, the new principal values
    const V pn = 0.5 * (best[1] + best[0]), rn = 0.5 * (best[1] - best[0]);
    const V inv_r = one / r, c2 = r > 0 ? a * inv_r : one, s2xy = r > 0 ? xy * inv_r : zero;
    xx = done ? pn + rn * c2 : xx;
    yy = done ? pn - rn * c2 : yy;
    xy = done ? rn * s2xy : xy;
    zz = done ? best[2] : zz;
    d_gamma = done ? best_gamma : d_gamma;
    return bits(done);
}
// eq. 6's consult of the Mohr-Coulomb points q .. q + N k - 1 of material mc (the largest
// whole number of groups of N before qend), which hold their elastic trials (the AVX2
// point loop's, consult_block in Simulation::run_points): the elastic test, the closed-form shear return
// and the search's first two sets (an edge, the apex line), then one_point(r, trial) (the
// one-point test and return, mohr_consult, and the stress stored) for a lane those do not
// settle. Returns where it stopped (the caller consults the last points). Own: each point's
// own strength (scatter); vol0_of(g): V0 of group g. A point's consult reads and writes that
// point only; each lane's operations are those of the one-point code. The lanes the closed
// form leaves go on at once (edge_return, then the one-point code): a second pass over the
// groups holding them, which made the elastic test and the return again to find what
// edge_return needs, was no faster (few groups of four hold one).
template <bool Own, class Vol0, class OnePoint>
LPFDM_LANE inline long consult(const MaterialConstants& mc, long q, const long qend, const ConsultArrays& a, const Vol0& vol0_of, const OnePoint& one_point) {
    // Local pointers (the stores of the yielded flags, through bytes, may change any object)
    double *psxx = a.sxx, *psyy = a.syy, *psxy = a.sxy, *pszz = a.szz;
    const double* pvol = a.vol;
    const std::uint16_t* pgroup = a.group;
    const double *pc0 = a.c0, *pnphi = a.n_phi, *psqrt = a.sqrt_n_phi;
    std::uint8_t* pyielded = a.yielded;
    double *pshear = a.plastic_shear, *pwork = a.plastic_work;
    // pyielded[r + l] != 0 in lane l (one word: byte l is lane l's, x86 being little-endian)
    using Word = std::conditional_t<N == 4, std::uint32_t, std::uint64_t>;
    auto yielded_lanes = [&](long r, M& soft) LPFDM_LANE {
        Word w;
        std::memcpy(&w, pyielded + r, sizeof w);
        soft = M(((M{} + static_cast<long long>(w)) & kLaneByte) != 0);
    };
    // strength_of, N points at once: the same operations in each lane
    auto strength = [&](long r, V& np, V& two_c_sq) LPFDM_LANE {
        V c0, sq;
        if constexpr (Own) {
            load(pc0 + r, c0); load(pnphi + r, np); load(psqrt + r, sq);
        } else {
            splat(mc.c, c0); splat(mc.n_phi, np); splat(mc.sqrt_n_phi, sq);
        }
        M soft;
        yielded_lanes(r, soft);
        const double keep = 1 - mc.soften;
        const V c = soft ? c0 * keep : c0;
        two_c_sq = 2 * c * sq;  // two_c_sqrt_n: strength_of sets sqrt_n_phi (its test cost 3 %)
    };
    // record_yield of lanes `lanes` (bits), returned from the trials t_* to xx .. zz with
    // plastic shear d_gamma: the same operations
    auto record = [&](long r, int lanes, const V& xx, const V& yy, const V& xy, const V& zz, const V& t_xx, const V& t_yy, const V& t_xy, const V& t_zz, const V& d_gamma) LPFDM_LANE {
        V work;  // compliance_product(mc, s, trial - s)
        compliance_product(mc, xx, yy, xy, zz, V(t_xx - xx), V(t_yy - yy), V(t_xy - xy), V(t_zz - zz), work);
        V v0{};  // the lanes' groups' V0: one look-up where they are one group (a word holds four)
        std::uint64_t g[N / 4];
        std::memcpy(g, pgroup + r, sizeof g);
        bool one = true;
        for (int w = 0; w < N / 4; ++w) one &= g[w] == (g[0] & 0xffff) * 0x0001000100010001ULL;
        if (one) splat(vol0_of(int(g[0] & 0xffff)), v0);
        else for (int l = 0; l < N; ++l) v0[l] = vol0_of(pgroup[r + l]);
        M m;
        lane_mask(lanes, m);
        V gamma, pw, vol;
        load(pshear + r, gamma); load(pwork + r, pw); load(pvol + r, vol);
        const V vk = a.at_vol0 ? v0 : v0 < vol ? v0 : vol;  // energy_volume: V0, or std::min(vol, vol0)
        gamma = m ? gamma + d_gamma : gamma;
        pw = m ? pw + vk * work : pw;
        store(pshear + r, gamma); store(pwork + r, pw);
        // softening from the next consult: 1 where a lane yielded (words, no branch: lanes yield at random)
        static constexpr std::uint32_t kLaneBytes[16] = {0x0u, 0xffu, 0xff00u, 0xffffu, 0xff0000u, 0xff00ffu, 0xffff00u, 0xffffffu,
                                                         0xff000000u, 0xff0000ffu, 0xff00ff00u, 0xff00ffffu, 0xffff0000u, 0xffff00ffu, 0xffffff00u, 0xffffffffu};
        for (int w = 0; w < N / 4; ++w) {
            std::uint32_t y;
            std::memcpy(&y, pyielded + r + 4 * w, 4);  // pyielded[r + 4 w + l] in byte l
            const std::uint32_t set = kLaneBytes[lanes >> (4 * w) & 15];
            y = (y & ~set) | (0x01010101u & set);
            std::memcpy(pyielded + r + 4 * w, &y, 4);
        }
    };
    constexpr int all = (1 << N) - 1;
    for (; q + N <= qend; q += N) {
        V xx, yy, xy, zz, np, two_c_sq, radius, d_gamma;
        load(psxx + q, xx); load(psyy + q, yy); load(psxy + q, xy); load(pszz + q, zz);
        strength(q, np, two_c_sq);
        int settled = inside(xx, yy, xy, zz, np, two_c_sq, radius);
        if (settled == all) continue;  // every lane inside: the trials stand
        const V t_xx = xx, t_yy = yy, t_xy = xy, t_zz = zz;
        Found found;
        settled = shear_return(xx, yy, xy, zz, radius, np, two_c_sq, mc.n_psi, mc.tension, mc.a1, mc.a2, d_gamma, found);
        if (const int sh = settled >> N) record(q, sh, xx, yy, xy, zz, t_xx, t_yy, t_xy, t_zz, d_gamma);
        int left = ~settled & all;
        if (left) {  // an edge or the apex line (the search's first two sets), from the trials
            V ex = t_xx, ey = t_yy, exy = t_xy, ez = t_zz;
            if (const int edge = edge_return(ex, ey, exy, ez, radius, np, two_c_sq, mc.n_psi, mc.a1, mc.a2, found, left, d_gamma)) {
                M done;
                lane_mask(edge, done);
                xx = done ? ex : xx; yy = done ? ey : yy; xy = done ? exy : xy; zz = done ? ez : zz;
                record(q, edge, ex, ey, exy, ez, t_xx, t_yy, t_xy, t_zz, d_gamma);
                left &= ~edge;
            }
        }
        store(psxx + q, xx); store(psyy + q, yy); store(psxy + q, xy); store(pszz + q, zz);
        for (int l = 0; left; ++l, left >>= 1)  // the lanes still left: the one-point code, on the trial
            if (left & 1) one_point(q + l, Stress{t_xx[l], t_yy[l], t_xy[l], t_zz[l]});
    }
    return q;
}
#undef LPFDM_LANE
}  // namespace lanes
using MohrLanes = lanes::Found;
// The lanes' functions as functions of their own, for the tests (built for AVX2).
__attribute__((target("avx2"))) inline int mohr_inside_lanes(const v4d& xx, const v4d& yy, const v4d& xy, const v4d& zz, const v4d& np, const v4d& two_c_sq, v4d& r) {
    return lanes::inside(xx, yy, xy, zz, np, two_c_sq, r);
}
__attribute__((target("avx2"))) inline int mohr_return_lanes(v4d& xx, v4d& yy, v4d& xy, v4d& zz, const v4d& r, const v4d& np, const v4d& two_c_sq, double n_psi, double tension, double a1, double a2, v4d& d_gamma, MohrLanes& found) {
    return lanes::shear_return(xx, yy, xy, zz, r, np, two_c_sq, n_psi, tension, a1, a2, d_gamma, found);
}
__attribute__((target("avx2"))) inline int mohr_edge_lanes(v4d& xx, v4d& yy, v4d& xy, v4d& zz, const v4d& r, const v4d& np, const v4d& two_c_sq, double n_psi, double a1, double a2, const MohrLanes& m, int left, v4d& d_gamma) {
    return lanes::edge_return(xx, yy, xy, zz, r, np, two_c_sq, n_psi, a1, a2, m, left, d_gamma);
}
#endif
// f(i, Tag<T>) for i = i0 .. i1 - 1: with Wide (std::true_type, inside a function built for
// AVX2) four at a time in the lanes of a vector (T = v4d), the rest one at a time.
template <class Wide, class F>
LPFDM_INLINE inline void sweep(int i0, int i1, Wide, const F& f) {
    int i = i0;
#if LPFDM_WIDE
    if constexpr (Wide::value)
        for (; i + 4 <= i1; i += 4) f(i, Tag<v4d>{});
#endif
    for (; i < i1; ++i) f(i, Tag<double>{});
}
}  // namespace detail
#if LPFDM_WIDE

LPFDM_INLINE inline void Simulation::CellSums::add_four(double pm, double vol0, const detail::v4d& vol, const detail::v4d& sxx, const detail::v4d& syy, const detail::v4d& sxy, double& mass) {
    detail::v4d acc = {v, xx, yy, xy};
    detail::add_four(acc, vol, sxx, syy, sxy, vol0);  // eq. 8
    v = acc[0]; xx = acc[1]; yy = acc[2]; xy = acc[3];
    for (int l = 0; l < 4; ++l) { m += pm; mass += pm; }  // eq. 7
}
#endif
namespace detail {
// Work shared by threads in team contiguous blocks, block u from was(u) to was(u + 1), took
// seconds(u) each. When the slowest took more than 3 % above the mean, the inner edges
// now[1 .. team-1] move halfway towards equal shares of the total time, the time of each
// block taken as spread evenly over it (halfway: the times are those of one step, and
// noisy). Returns whether they moved. The threads' results may not depend on the edges.
// (3 %: with 10 %, two threads may differ by a fifth of their mean time on every step.)
template <class T, class Was, class Seconds>
bool balance(int team, const Was& was, const Seconds& seconds, T* now) {
    double total = 0, slowest = 0;
    for (int u = 0; u < team; ++u) { total += seconds(u); slowest = std::max(slowest, seconds(u)); }
    if (!(slowest > 1.03 * total / team)) return false;
    double before = 0;  // the time of blocks 0 .. u-1
    int u = 0;
    for (int j = 1; j < team; ++j) {
        const double share = total * j / team;
        while (u + 1 < team && before + seconds(u) < share) before += seconds(u++);
        const double f = seconds(u) > 0 ? std::min(1.0, (share - before) / seconds(u)) : 0.5;
        const T even = was(u) + T(f * double(was(u + 1) - was(u)));
        now[j] = was(j) + (even - was(j)) / 2;
    }
    return true;
}
}  // namespace detail
#if defined(LPFDM_IMPLEMENTATION)  // out-of-line definitions (left out by LPFDM_INTERNALS alone)

LPFDM_DEF void Simulation::step() {
    if (step_ == 0) start_energy();
    if (profiling_) { step_profiled(); return; }
    if (reference_only()) { step_reference(); return; }
    cell_strains();    // eq. 5a-5f
    point_pass();      // eq. 6, Jaumann by eq. 5f, volume, eq. 7a/7b; eq. 7, 8
    water_pass();      // WATER (as step_reference)
    nodal_forces();    // virtual work transpose of eq. 5, gravity eq. 10
    load_forces();     // LOAD
    compensate();      // eq. 12
    integrate();       // eq. 13-14, fixed nodes, moving walls
    load_work();
    shift_points();  // SHIFT
    parked_ += parking_.take();
    held_ += holding_.take();
    ++step_;
    if (reorder_due()) reorder_points();  // storage only (REORDER)
}

inline void Simulation::step_profiled() {
    using clock = std::chrono::steady_clock;
    const bool ref = reference_only();
    // A switch, not an array of member pointers: g++ 12 -O1 with ASan and UBSan
    // together miscompiles the indexed member-pointer call (a wild index, a crash).
    for (int k = 0; k < kPhases; ++k) {
        const auto t0 = clock::now();
        switch (k) {
        case 0: ref ? reference_cell_strains() : cell_strains(); break;
        case 1: ref ? reference_points() : point_pass(); water_pass(); break;
        case 2: ref ? reference_nodal_forces() : nodal_forces(); load_forces(); break;
        case 3: ref ? reference_compensate() : compensate(); break;
        default: ref ? reference_integrate() : integrate(); load_work(); shift_points(); break;
        }
        phase_s_[k] += std::chrono::duration<double>(clock::now() - t0).count();
    }
    parked_ += parking_.take();
    held_ += holding_.take();
    ++step_;
    if (reorder_due()) {  // timed with the points' phase
        const auto t0 = clock::now();
        reorder_points();
        phase_s_[1] += std::chrono::duration<double>(clock::now() - t0).count();
    }
}

LPFDM_DEF void Simulation::point_pass() {
    if (modes_.mapping == Mapping::Smooth) smooth_point_pass();
    else if (serial() || !advance_parted()) advance_points();
}

inline bool Simulation::serial() const {
#if defined(_OPENMP)
    return team_ == 1 || p_.size() <= 4096 || modes_.user;
#else
    return true;
#endif
}

LPFDM_DEF const char* Simulation::phase_name(int k) {
    static const char* names[kPhases] = {"cell_strains", "points", "nodal_forces", "compensate", "integrate"};
    return names[k];
}

LPFDM_DEF bool Simulation::have_wide() {
#if LPFDM_WIDE
    return __builtin_cpu_supports("avx2");
#else
    return false;
#endif
}

LPFDM_DEF void Simulation::set_wide(bool on) {
    wide_ = on && have_wide() && kernel_ != Kernel::Reference;
    choose_point_loop();
}

template <class F> inline void Simulation::each_row(const F& f, int j) const {
#if LPFDM_WIDE
    if (wide_) { row_wide(f, j); return; }
#endif
    f(j, std::false_type{});
}

inline void Simulation::add_listed(int team) {
    for (int u = 0; u < team; ++u) {
        const Part& a = parts_[std::size_t(u)];
        for (long d = 0; d < a.listed; ++d) map_point(std::size_t(p_.listed[std::size_t(a.list_at + d)]));
    }
}

#if LPFDM_WIDE
LPFDM_INLINE inline void Simulation::gather_mean(const detail::v4i& n1, detail::v4d& umx, detail::v4d& umy) const {
    using detail::v4d;
    const double *u = dux_.data(), *v = duy_.data();
    const detail::v4i n3 = n1 + (mx_ + 1);
    const v4d ux1 = {u[n1[0]], u[n1[1]], u[n1[2]], u[n1[3]]}, ux2 = {u[n1[0] + 1], u[n1[1] + 1], u[n1[2] + 1], u[n1[3] + 1]};
    const v4d ux3 = {u[n3[0]], u[n3[1]], u[n3[2]], u[n3[3]]}, ux4 = {u[n3[0] + 1], u[n3[1] + 1], u[n3[2] + 1], u[n3[3] + 1]};
    const v4d uy1 = {v[n1[0]], v[n1[1]], v[n1[2]], v[n1[3]]}, uy2 = {v[n1[0] + 1], v[n1[1] + 1], v[n1[2] + 1], v[n1[3] + 1]};
    const v4d uy3 = {v[n3[0]], v[n3[1]], v[n3[2]], v[n3[3]]}, uy4 = {v[n3[0] + 1], v[n3[1] + 1], v[n3[2] + 1], v[n3[3] + 1]};
    mean_of_four(ux1, ux2, ux3, ux4, umx); mean_of_four(uy1, uy2, uy3, uy4, umy);
}

inline detail::ConsultArrays Simulation::consult_arrays(const PointArrays& a) {
    return {a.sxx, a.syy, a.sxy, a.szz, a.vol, a.group, p_.c0.data(), p_.n_phi.data(), p_.sqrt_n_phi.data(), p_.yielded.data(), p_.plastic_shear.data(), p_.plastic_work.data(), modes_.advect == Advect::Flip};
}

template <bool Own> inline void Simulation::consult_one(const MaterialConstants& mc, long r, Stress s, const PointArrays& a) {
    mohr_consult<Own>(mc, std::size_t(r), a.vol[r], s);
    a.sxx[r] = s.xx; a.syy[r] = s.yy; a.sxy[r] = s.xy; a.szz[r] = s.zz;
}
#endif

// --------------------------------------------------------- the fast kernel ---

// Rows j0 .. j1-1 of a lattice phase, f(j) for each, by threads when they visit more than
// 4 096 cells or nodes in all (work; the same number as the point pass's threshold in
// points): a loop left to one thread in a threaded run is slow (it reads from the other
// core's cache what the other thread wrote in the phase before). Each row writes only
// its own nodes or cells, so which thread takes a row changes no number: thread u takes a
// block of rows, and the blocks follow the threads' times (detail::balance), as rows cost
// unequal amounts (eq. 12 costs more where nodes cross cells).
template <class F>
inline void Simulation::by_rows([[maybe_unused]] RowLoop loop, int j0, int j1, [[maybe_unused]] long work, const F& f) {
#if defined(_OPENMP)
    RowBlocks& b = row_blocks_[loop];
    const int cap = std::min(team_, int(b.seconds.size()));
    if (work > 4096 && cap > 1 && !omp_in_parallel()) {
        const int n = j1 - j0;
        int team = 1;
        LPFDM_OMP(omp parallel num_threads(cap))
        {
            const int nt = omp_get_num_threads(), id = omp_get_thread_num();
            const bool known = nt == b.team;  // else even blocks
            auto edge = [&](int u) { return j0 + int((known ? b.at[std::size_t(u)] : double(u) / nt) * n + 0.5); };
            const int a = edge(id), e = edge(id + 1);
            const double t0 = omp_get_wtime();
            for (int j = a; j < e; ++j) f(j);
            b.seconds[std::size_t(id)] = omp_get_wtime() - t0;
            b.rows[std::size_t(id)] = a;
            if (id == 0) team = nt;
        }
        if (team != b.team) {
            for (int u = 0; u <= team; ++u) b.at[std::size_t(u)] = double(u) / team;
            b.team = team;
        }
        b.rows[std::size_t(team)] = j1;
        if (n > 0)
            row_moves_ += detail::balance(team, [&](int u) { return double(b.rows[std::size_t(u)] - j0) / n; },
                                          [&](int u) { return b.seconds[std::size_t(u)]; }, b.at.data());
        return;
    }
#endif
    for (int j = j0; j < j1; ++j) f(j);
}

// eq. 5a-5f for every cell that a point or a compensated node may read, plus the
// rotation of eq. 5f as an exact orthogonal matrix (Cayley form: no trigonometry).
LPFDM_DEF void Simulation::cell_strains() {
    strained_ = occupied_.grow(2, mx_, my_);
    const Range r = strained_;
    const int mx = mx_;
    const double h = 0.5 * invL_;
    const double* ux = dux_.data();
    const double* uy = duy_.data();
    const double* cm = cmass_.data();
    CellStrain* cs = strain_.data();
    double *hgx = hgx_.data(), *hgy = hgy_.data();
    const bool hourglass = modes_.hourglass;
    // Cell (i, j), or the cells i .. i + 3 in the lanes of a vector T.
    auto cells = [&](int i, int j, auto tag) LPFDM_INLINE {
        using T = typename decltype(tag)::type;
        const int c = j * mx + i, n1 = j * (mx + 1) + i;
        T xx, yy, xy, yx, rc, rs;
        cell_strain(ux, uy, n1, mx + 1, h, xx, yy, xy, yx);  // eq. 5a-5d
        jaumann_rotation(T(0.5 * (yx - xy)), rc, rs);        // eq. 5f (theta = (yx - xy) / 2)
        // An empty cell holds no material to strain; its "increments" between moving
        // and resting nodes would make eq. 12 brake every node on a free surface: no
        // strain, no rotation there (what eq. 5f gives for zero).
        T mass;
        detail::load(cm + c, mass);
        const auto full = mass > 0;
        const T zero{}, unit = zero + 1;
        xx = full ? xx : zero; yy = full ? yy : zero; xy = full ? xy : zero; yx = full ? yx : zero;
        rc = full ? rc : unit; rs = full ? rs : zero;
        if constexpr (std::is_same_v<T, double>) {
            cs[c] = CellStrain{xx, yy, xy, yx, rc, rs};
        } else {  // four records of six doubles: 24 in a row, stored as six vectors
#if LPFDM_WIDE
            using detail::v4d;
            const v4d a = LPFDM_SHUFFLE(xx, yy, 0, 4, 2, 6), b = LPFDM_SHUFFLE(xx, yy, 1, 5, 3, 7);  // xx yy of cells 0 2, 1 3
            const v4d d = LPFDM_SHUFFLE(xy, yx, 0, 4, 2, 6), e = LPFDM_SHUFFLE(xy, yx, 1, 5, 3, 7);  // xy yx
            const v4d p = LPFDM_SHUFFLE(rc, rs, 0, 4, 2, 6), q = LPFDM_SHUFFLE(rc, rs, 1, 5, 3, 7);  // rc rs
            const v4d c1 = LPFDM_SHUFFLE(b, e, 0, 1, 4, 5), c3 = LPFDM_SHUFFLE(b, e, 2, 3, 6, 7);  // xx yy xy yx of cells 1, 3
            static_assert(sizeof(CellStrain) == 6 * sizeof(double), "six doubles, no padding");
            double* const at = reinterpret_cast<double*>(cs + c);
            // Six stores of their own (an array of the six, stored in a loop, went through
            // the stack: GCC wrote it there and copied it out in halves).
            detail::store(at, v4d(LPFDM_SHUFFLE(a, d, 0, 1, 4, 5))); detail::store(at + 4, v4d(LPFDM_SHUFFLE(p, c1, 0, 1, 4, 5)));
            detail::store(at + 8, v4d(LPFDM_SHUFFLE(c1, q, 2, 3, 4, 5))); detail::store(at + 12, v4d(LPFDM_SHUFFLE(a, d, 2, 3, 6, 7)));
            detail::store(at + 16, v4d(LPFDM_SHUFFLE(p, c3, 2, 3, 4, 5))); detail::store(at + 20, v4d(LPFDM_SHUFFLE(c3, q, 2, 3, 6, 7)));
#endif
        }
        if (hourglass) {  // the checkerboard part h = (+1, -1, -1, +1)/4 that eq. 5 cannot see
            T gx, gy;
            checkerboard_mode(ux, uy, n1, mx + 1, gx, gy);
            detail::store(hgx + c, full ? gx : zero);
            detail::store(hgy + c, full ? gy : zero);
        }
    };
    auto row = [&](int j, auto wide) LPFDM_INLINE { detail::sweep(r.i0, r.i1, wide, [&](int i, auto tag) LPFDM_INLINE { cells(i, j, tag); }); };
    by_rows(kStrainRows, r.j0, r.j1, r.size(), [&](int j) { each_row(row, j); });
}

// The points' phase by one thread: eq. 6 (one consult of the constitutive model per
// point), the Jaumann rotation by eq. 5f, the volume change, the motion of eq. 7a/7b,
// and eq. 7 and 8 into the cell each point lands in, in one pass (reference_points
// does the same, one point at a time; this pass takes runs of points sharing a cell).
inline void Simulation::advance_points() {
    clear_cells();
    Part all;
    Landing t;
    advance_range(0, long(p_.size()), all, t);
    return_s_ += all.return_seconds; returned_ += all.returned;
    departed_ = std::size_t(t.departed);
    if (departed_) remove_departed();
    mass_in_ = t.mass;
    occupied_ = landed(t);
}

// advance_points by threads. Thread u
// moves the points of its chunk (a contiguous range) and adds those landing in its part
// of the cells (own_lo .. own_hi-1 of its Part; the parts follow one another in cell
// order) directly; a point landing in another part is listed, and the lists are added
// after the pass in chunk order. Each cell sum then takes its terms in point order, the
// same as the serial pass, unless a chunk landed in a higher chunk's part: that higher
// chunk's points went in first. That is checked after the pass, and then the step's sums
// are cleared and made again by map_to_lattice (the points have moved already): the same
// numbers either way, only slower. A part ends a row and two cells above the highest cell
// the chunk's points lie in (known from the last step's pass, else looked up): beyond the
// reach of a point that moves at most one cell. With ADVECT POINTS each point also keeps
// the increment it carries and the cell it left (Points::carry_*), for a listed point and
// for the mapping made again. Returns false when it cannot run (one thread; more threads
// than at set-up, or 4 096 points or fewer then; dynamic or nested teams); point_pass
// then takes advance_points.
inline bool Simulation::advance_parted() {
#if defined(_OPENMP)
    const long n = long(p_.size());
    const int want = team_;
    // A team smaller than asked for (dynamic teams, or inside another parallel region) would
    // make parts for threads that do not come: one thread then (advance_points).
    if (want < 2 || want > int(parts_.size()) || omp_get_dynamic() || omp_in_parallel()) return false;
    if (chunk_team_ != want) {  // a new thread count: even chunks
        for (int u = 0; u <= want; ++u) chunk_at_[std::size_t(u)] = n * u / want;
        chunk_team_ = want;
        parts_known_ = false;
    } else if (chunk_at_[std::size_t(want)] != n) {  // points left: the chunks in proportion
        const long was = std::max(1L, chunk_at_[std::size_t(want)]);
        for (int u = 0; u <= want; ++u) chunk_at_[std::size_t(u)] = std::min(n, chunk_at_[std::size_t(u)] * n / was);
        chunk_at_[std::size_t(want)] = n;
        parts_known_ = false;
    }
    int lo = 0;
    for (int u = 0; u < want; ++u) {
        const long k0 = chunk_at_[std::size_t(u)], k1 = chunk_at_[std::size_t(u + 1)];
        int hi = std::numeric_limits<int>::max();
        if (u + 1 < want) {
            int top = -1;  // the highest cell the chunk's points lie in, or above it
            auto look = [&](long a, long b) { for (long k = a; k < b; ++k) top = std::max(top, p_.cell[std::size_t(k)]); };
            if (parts_known_) {  // the last step's chunk u, o0 .. o1-1, and the points it did not hold
                const long o0 = parts_[std::size_t(u)].list_at, o1 = parts_[std::size_t(u + 1)].list_at;
                if (std::max(k0, o0) < std::min(k1, o1)) top = landings_[std::size_t(u)].cmax;
                look(k0, std::min(k1, o0));
                look(std::max(k0, o1), k1);
            } else {
                look(k0, k1);
            }
            hi = std::max(lo, top + mx_ + 2);
        }
        parts_[std::size_t(u)].own_lo = lo;
        parts_[std::size_t(u)].own_hi = hi;
        lo = hi;
    }
    int team = 1;
    LPFDM_OMP(omp parallel num_threads(want))
    {
        const int nt = omp_get_num_threads(), id = omp_get_thread_num();
        const long k0 = nt == want ? chunk_at_[std::size_t(id)] : n * id / nt, k1 = nt == want ? chunk_at_[std::size_t(id + 1)] : n * (id + 1) / nt;
        const double t0 = omp_get_wtime();
        Part mine;
        mine.own_lo = parts_[std::size_t(id)].own_lo;
        if (id + 1 < nt) mine.own_hi = parts_[std::size_t(id)].own_hi;  // the last chunk: every cell above
        mine.list_at = k0;
        // The part's cells are this thread's alone: it clears them (clear_cells) itself.
        if (!occupied_.empty())
            for (int j = std::max(occupied_.j0, mine.own_lo / mx_), j1 = int(std::min<long>(occupied_.j1, mine.own_hi / mx_ + 1L)); j < j1; ++j)
                clear_row(j, mine.own_lo, mine.own_hi);
        Landing got;
        advance_range(k0, k1, mine, got);
        mine.seconds = omp_get_wtime() - t0;
        parts_[std::size_t(id)] = mine;
        landings_[std::size_t(id)] = got;
        if (id == 0) team = nt;
    }
    Landing t;
    bool clash = false;
    for (int u = 0; u < team; ++u) {
        clash |= landings_[std::size_t(u)].cmax >= parts_[std::size_t(u)].own_hi;  // landed in a higher chunk's part
        parted_.listed += parts_[std::size_t(u)].listed;
        return_s_ += parts_[std::size_t(u)].return_seconds; returned_ += parts_[std::size_t(u)].returned;  // (thread seconds)
        t.merge(landings_[std::size_t(u)]);
    }
    if (!clash) add_listed(team);
    departed_ = std::size_t(t.departed);
    if (departed_) remove_departed();
    occupied_ = landed(t);  // every cell written
    mass_in_ = t.mass;
    parts_known_ = t.departed == 0 && !clash && team == want;
    if (team != want) chunk_team_ = 0;
    // The chunks took unequal times (points that cross cells or yield cost more, and they
    // gather in parts of a scene): the next step's chunks follow the times.
    if (parts_known_)
        detail::balance(team, [&](int u) { return u < team ? parts_[std::size_t(u)].list_at : n; },
                        [&](int u) { return parts_[std::size_t(u)].seconds; }, chunk_at_.data());
    ++parted_.steps;
    if (clash) {
        ++parted_.clashes;
        map_points();
    }
    return true;
#else
    return false;
#endif
}

// Points k0 .. k1-1. The points are stored cell by cell and mostly stay so (they are
// created that way, sorted so every REORDER steps, and cross a cell edge rarely), so the
// loop walks runs of points that share a cell: the cell's strain, rotation, nodes and
// elastic stress increment are read once per run. The sums of the run's cell are kept in
// registers while its points stay in it and written back when the run ends; every sum
// still takes its terms in point order, so the result is the same bit for bit as a plain
// loop over points. (The AVX2 loop of a scene with a Mohr-Coulomb material goes four
// points at a time across cells instead: run_points' move_block and land_block.)
// Requires p_.cell[k] to be the cell holding (x[k], y[k]) (as after every step).
// One instantiation per motion rule and transfer, so the loop holds only what it uses.
inline void Simulation::advance_range(long k0, long k1, Part& part, Landing& t) { (this->*run_)(k0, k1, part, t); }

// The version of the point loop this scene runs, chosen once (at set-up, and when set_wide
// changes the choice): the motion rule, ADVECT POINTS, and AVX2.
inline void Simulation::choose_point_loop() {
    // The default motion rule (MOTION CENTRE without ADVECT POINTS) has builds of its own;
    // the options (MOTION PAPER or BILINEAR, ADVECT POINTS) share one that asks modes_ as it
    // goes (Motion::Default): each build of the loop adds to the build time of every program.
    const bool options = modes_.motion != Motion::Centre || modes_.advect == Advect::Points;
    run_ = options ? &Simulation::advance_run<Motion::Default> : &Simulation::advance_run<Motion::Centre>;
#if LPFDM_WIDE
    if (wide_ && !options) run_ = &Simulation::advance_run_wide;  // AVX2
#endif
}

template <Motion M>
inline void Simulation::advance_run(long k0, long k1, Part& part, Landing& landing) { run_points<M, false>(k0, k1, part, landing); }
#if LPFDM_WIDE
// Two versions: the one with blocks (a scene with a Mohr-Coulomb material) in the same
// function slowed the run-by-run loop of an elastic scene (the compiler's registers), so
// each has a function of its own.
__attribute__((target("avx2"), noinline)) inline void Simulation::advance_blocks_wide(long k0, long k1, Part& part, Landing& landing) { run_points<Motion::Centre, true, true>(k0, k1, part, landing); }
__attribute__((target("avx2"))) inline void Simulation::advance_run_wide(long k0, long k1, Part& part, Landing& landing) {
    if (mohr_groups_) advance_blocks_wide(k0, k1, part, landing);
    else run_points<Motion::Centre, true>(k0, k1, part, landing);
}

// eq. 6's Mohr-Coulomb consult of points q .. qend-1 of material mc, which hold their
// elastic trials (the AVX2 point loop's, consult_block): four points per AVX2 register
// (detail::lanes::consult) and the last one to three by the one-point code. Own: each point's own strength (scatter).
template <bool Own>
__attribute__((target("avx2"))) inline void Simulation::consult_lanes(const MaterialConstants& mc, long q, const long qend, const PointArrays& a) {
    auto one_point = [&](long r, Stress s) { consult_one<Own>(mc, r, s, a); };
    q = detail::lanes::consult<Own>(mc, q, qend, consult_arrays(a), [&](int g) { return groups_[std::size_t(g)].vol0; }, one_point);
    for (; q < qend; ++q) one_point(q, Stress{a.sxx[q], a.syy[q], a.sxy[q], a.szz[q]});
}
#endif

#if LPFDM_WIDE
namespace detail {
// square_overlap of four points along one axis, in the lanes of AVX2 registers: the same
// operations in the same order, each branch taken by a blend (a: the first cell, as a
// double). A lane whose point lies outside the lattice gets numbers to throw away.
__attribute__((always_inline, target("avx2"))) inline void square_overlap_lanes(const v4d& x, const v4d& l, double L, int m, v4d& a, v4d& w0, v4d& w1, v4d& c0, v4d& c1) {
    auto pick = [](const v4m& on, const v4d& yes, const v4d& no, v4d& out) LPFDM_INLINE { out = v4d((v4m(yes) & on) | (v4m(no) & ~on)); };
    const v4d lo = x - l, hi = x + l;
    const v4d t = lo / L;
    a = __builtin_convertvector(v4i(__builtin_ia32_cvttpd2dq256(t)), v4d);  // int(t)
    pick(t < a, a - 1, a, a);                                         // floor(t)
    const v4d edge = (a + 1) * L, one = v4d{} + 1, zero{};
    const v4m inside = hi <= edge;
    pick(inside, one, (edge - lo) / (hi - lo), w0);
    pick(inside, zero, (hi - edge) / (hi - lo), w1);
    pick(inside, x, 0.5 * (lo + edge), c0);
    pick(inside, zero, 0.5 * (edge + hi), c1);
    const v4m left = a < 0;  // the part left of the lattice
    pick(left, zero, a, a); pick(left, one, w0, w0); pick(left, zero, w1, w1); pick(left, 0.5 * (0 + hi), c0, c0);
    const v4m right = (a >= double(m - 1)) & (w1 > 0);  // right of it
    pick(right, v4d{} + double(m - 1), a, a); pick(right, one, w0, w0); pick(right, zero, w1, w1); pick(right, 0.5 * (lo + m * L), c0, c0);
}
}  // namespace detail

// smooth_map's first pass for points b0 .. b1-1, four at a time with AVX2: each point's
// cell (cell_holding) and square (overlap_of) where it is now, the same numbers; a point
// that left the lattice (or is not finite) the empty square; the last one to three by one(k).
template <class F>
__attribute__((target("avx2"))) inline void Simulation::squares_lanes(const long b0, const long b1, const F& one) {
    using detail::v4d;
    using detail::v4m;
    const double X = mx_ * L_, Y = my_ * L_;
    long k = b0;
    for (; k + 4 <= b1; k += 4) {
        v4d x, y;
        detail::load(p_.x.data() + k, x); detail::load(p_.y.data() + k, y);
        const std::uint16_t* g = p_.group.data() + k;
        const v4d l = {groups_[g[0]].half, groups_[g[1]].half, groups_[g[2]].half, groups_[g[3]].half};
        const int in = detail::lane_bits((x >= 0) & (x < X) & (y >= 0) & (y < Y));  // cell_holding's test
        v4d ax, wx0, wx1, cx0, cx1, ay, wy0, wy1, cy0, cy1;
        detail::square_overlap_lanes(x, l, L_, mx_, ax, wx0, wx1, cx0, cx1);
        detail::square_overlap_lanes(y, l, L_, my_, ay, wy0, wy1, cy0, cy1);
        const v4d u = x * invL_, v = y * invL_;
        for (int q = 0; q < 4; ++q) {
            const std::size_t r = std::size_t(k + q);
            if (!(in >> q & 1)) { p_.cell[r] = -1; overlap_[r] = detail::Overlap{}; continue; }
            p_.cell[r] = cell(std::min(mx_ - 1, int(u[q])), std::min(my_ - 1, int(v[q])));
            detail::Overlap& o = overlap_[r];
            o.a = int(ax[q]); o.b = int(ay[q]);
            o.wx[0] = wx0[q]; o.wx[1] = wx1[q]; o.wy[0] = wy0[q]; o.wy[1] = wy1[q];
            o.cx[0] = cx0[q]; o.cx[1] = cx1[q]; o.cy[0] = cy0[q]; o.cy[1] = cy1[q];
        }
    }
    for (; k < b1; ++k) one(std::size_t(k));
}
#endif

#if LPFDM_WIDE
// flip_sums' band j0 .. j1-1 with AVX2: rec[4 n + q] += (w m) v[q], v = (vx, vy, 1, 0) of
// the point, w flip_weights' at each node in its order: a node's three sums in one
// register, one add where the one-value loop makes three, each lane the same operations.
__attribute__((target("avx2"))) inline void Simulation::flip_sums_lanes(const int j0, const int j1, double* rec, const double* vx, const double* vy) {
    using detail::v4d;
    for (std::size_t k = 0, n = p_.size(); k < n; ++k) {
        const double m = groups_[p_.group[k]].mass;
        const v4d v = {vx[k], vy[k], 1.0, 0.0};
        flip_weights(k, [&](std::size_t u, double w) LPFDM_INLINE {
            double* r = rec + 4 * u;
            v4d sum;
            detail::load(r, sum);
            sum += w * m * v;
            detail::store(r, sum);
        }, j0, j1);
    }
}
#endif

#if LPFDM_WIDE
// smear_points' rows j0 .. j1-1 with AVX2: smear_point's terms for each part of each
// point's square, the same operations in the same order, added to the part's cell's sums
// side by side (cell_rec_: mass, V, V sxx, V syy | V sxy, the moments shx, shy, the
// centroid's u | its v), two registers and one double a part where the one-value loop
// makes nine adds; then the band's cells copied out to the arrays and their records
// zeroed. The arrays hold zeros in every cell a pass adds to (clear_cells, and for ADVECT
// FLIP's second mapping flip_second_half's zero_rows), so each takes the same terms in
// the same order from the same zero: the same bits.
template <Simulation::Smear S>
__attribute__((target("avx2"))) inline void Simulation::smear_lanes(const int j0, const int j1, Landing& t) {
    using detail::v4d;
    using detail::v4m;
    constexpr bool kMass = S != Smear::Stress, kStress = S != Smear::Mass;
    // the lanes this pass adds to: of the first register (m, V, V sxx, V syy) and the second
    constexpr v4m first = {kMass ? -1LL : 0, -1LL, kStress ? -1LL : 0, kStress ? -1LL : 0};
    constexpr v4m second = {kStress ? -1LL : 0, kStress ? -1LL : 0, kStress ? -1LL : 0, -1LL};
    double* rec = detail::aligned32(cell_rec_);
    const bool flip = modes_.advect == Advect::Flip;
    int lo = std::numeric_limits<int>::max(), hi = -1;  // the first and last cell this band added to, and their columns
    int imin = std::numeric_limits<int>::max(), imax = -1;  // (locals: through t they went to memory and back a part)
    for (std::size_t k = 0, n = p_.size(); k < n; ++k) {
        const detail::Overlap& o = overlap_[k];
        if (o.b >= j1 || o.b + 1 < j0) continue;  // its square's rows are b and b + 1
        const Group& g = groups_[p_.group[k]];
        const double v = std::min(p_.vol[k], g.vol0), m = g.mass;
        double sxx = 0, syy = 0, sxy = 0;
        if constexpr (kStress) {
            const double r = flip && v > 0 ? g.vol0 / v : 1.0;  // as smear_points
            sxx = r * p_.sxx[k]; syy = r * p_.syy[k]; sxy = r * p_.sxy[k];
        }
        const double p = 0.5 * (sxx + syy);
        each_part(o, [&](int ci, int cj, double px, double py, double w) LPFDM_INLINE {
            if (cj < j0 || cj >= j1) return;
            const int c = cell(ci, cj);
            const double ru = (px - ci * L_) * invL_ - 0.5, rv = (py - cj * L_) * invL_ - 0.5;
            const double wv = w * v;
            lo = std::min(lo, c); hi = std::max(hi, c);
            imin = std::min(imin, ci); imax = std::max(imax, ci);
            double* r = rec + 12 * std::size_t(c);
            v4d a, b;
            detail::load(r, a); detail::load(r + 4, b);
            const v4d ta = v4d{w, wv, wv, wv} * v4d{m, 1.0, sxx, syy};  // w m, V, V sxx, V syy
            const v4d tb = wv * v4d{sxy, (sxx - p) * rv + sxy * ru, sxy * rv + (syy - p) * ru, ru};
            a = first ? v4d(a + ta) : a;
            b = second ? v4d(b + tb) : b;
            detail::store(r, a); detail::store(r + 4, b);
            r[8] += wv * rv;
        });
    }
    if constexpr (S != Smear::Stress) {  // smear_point's box
        t.cmin = std::min(t.cmin, lo); t.cmax = std::max(t.cmax, hi);
        t.imin = std::min(t.imin, imin); t.imax = std::max(t.imax, imax);
    }
    double* const to[9] = {cmass_.data(), cvol_.data(), svxx_.data(), svyy_.data(), svxy_.data(), shx_.data(), shy_.data(), smu_.data(), smv_.data()};
    constexpr bool adds[9] = {kMass, true, kStress, kStress, kStress, kStress, kStress, true, true};
    if (hi < 0) return;
    for (int j = lo / mx_; j <= hi / mx_; ++j)  // the box of the cells touched, row by row
        for (int c = cell(imin, j); c <= cell(imax, j); ++c) {
            double* r = rec + 12 * std::size_t(c);
            for (int q = 0; q < 9; ++q)
                if (adds[q]) to[q][c] = r[q];
            for (int q = 0; q < 12; ++q) r[q] = 0;
        }
}
#endif

#if LPFDM_WIDE
// MAPPING SMOOTH's trials of points b0 .. b1-1 (each_point_consulted's block): Move,
// smooth_move<true> with MOTION BILINEAR; not Move, flip_second_strain<true>. Four points
// at a time in the lanes of an AVX2 register where four neighbours in storage share an
// elastic or Mohr-Coulomb group: smooth_strain (the square's node weights axis_shape, the
// nine nodes' increments, the B-bar trace over the parts each_part visits), eq. 5f, the
// volume and eq. 6's elastic trial (smooth_stress), and the motion with its edge stop, the
// same operations in the same order as those functions, so the same bits; the others one
// at a time by those functions.
template <bool Move>
__attribute__((target("avx2"))) inline void Simulation::smooth_lanes(const long b0, const long b1) {
    using detail::v4d;
    using detail::v4m;
    auto one = [&](long k) {
        if constexpr (Move) smooth_move<true>(std::size_t(k));
        else flip_second_strain<true>(std::size_t(k));
    };
    const double L = L_, invL = invL_;
    const bool half = !Move || modes_.advect == Advect::Flip;  // ADVECT FLIP: half the strain from each lattice
    const int row = mx_ + 1;
    const double *ux = dux_.data(), *uy = duy_.data(), *ct = centroid_trace_.data();
    long k = b0;
    for (; k + 4 <= b1; k += 4) {
        const std::uint16_t g = p_.group[std::size_t(k)];
        const MaterialConstants& mc = *group_consts_[g];
        if (p_.group[std::size_t(k + 1)] != g || p_.group[std::size_t(k + 2)] != g || p_.group[std::size_t(k + 3)] != g ||
            (mc.model != Model::Elastic && mc.model != Model::MohrCoulomb)) {
            for (long q = k; q < k + 4; ++q) one(q);
            continue;
        }
        // Each lane's square (overlap_), its nodes' increments, and its parts' traces (0
        // where a part has no weight: each_part skips it). Each vector is made from four
        // loads at once (values written lane by lane into a vector would go through memory).
        const detail::Overlap* o[4] = {&overlap_[std::size_t(k)], &overlap_[std::size_t(k + 1)], &overlap_[std::size_t(k + 2)], &overlap_[std::size_t(k + 3)]};
        const detail::Overlap &o0 = *o[0], &o1 = *o[1], &o2 = *o[2], &o3 = *o[3];
        const v4d wx[2] = {{o0.wx[0], o1.wx[0], o2.wx[0], o3.wx[0]}, {o0.wx[1], o1.wx[1], o2.wx[1], o3.wx[1]}};
        const v4d wy[2] = {{o0.wy[0], o1.wy[0], o2.wy[0], o3.wy[0]}, {o0.wy[1], o1.wy[1], o2.wy[1], o3.wy[1]}};
        const v4d cx[2] = {{o0.cx[0], o1.cx[0], o2.cx[0], o3.cx[0]}, {o0.cx[1], o1.cx[1], o2.cx[1], o3.cx[1]}};
        const v4d cy[2] = {{o0.cy[0], o1.cy[0], o2.cy[0], o3.cy[0]}, {o0.cy[1], o1.cy[1], o2.cy[1], o3.cy[1]}};
        const v4d ax0 = {o0.a * L, o1.a * L, o2.a * L, o3.a * L}, ax1 = {(o0.a + 1) * L, (o1.a + 1) * L, (o2.a + 1) * L, (o3.a + 1) * L};  // axis_shape's
        const v4d ay0 = {o0.b * L, o1.b * L, o2.b * L, o3.b * L}, ay1 = {(o0.b + 1) * L, (o1.b + 1) * L, (o2.b + 1) * L, (o3.b + 1) * L};
        int at[3][3][4];  // node of row m, column c, lane l (smooth_strain's)
        for (int l = 0; l < 4; ++l) {
            const int i2 = std::min(o[l]->a + 2, mx_) - o[l]->a;
            for (int m = 0; m < 3; ++m) {
                const int n = std::min(o[l]->b + m, my_) * row + o[l]->a;
                at[m][0][l] = n; at[m][1][l] = n + 1; at[m][2][l] = n + i2;
            }
        }
        v4d nu[3][3], nv[3][3], pw[2][2], pt[2][2];
        for (int m = 0; m < 3; ++m)
            for (int c = 0; c < 3; ++c) {
                const int* a = at[m][c];
                nu[m][c] = v4d{ux[a[0]], ux[a[1]], ux[a[2]], ux[a[3]]};
                nv[m][c] = v4d{uy[a[0]], uy[a[1]], uy[a[2]], uy[a[3]]};
            }
        for (int q = 0; q < 2; ++q)
            for (int r = 0; r < 2; ++r) {
                pw[q][r] = wx[r] * wy[q];  // each_part's w
                const int some = detail::lane_bits(pw[q][r] > 0);
                int c[4];
                for (int l = 0; l < 4; ++l) c[l] = some >> l & 1 ? cell(o[l]->a + r, o[l]->b + q) : 0;
                pt[q][r] = v4d{ct[c[0]], ct[c[1]], ct[c[2]], ct[c[3]]};
            }
        v4d sx[3], sy[3];
        detail::axis_shape(ax0, ax1, wx, cx, invL, sx);
        detail::axis_shape(ay0, ay1, wy, cy, invL, sy);
        v4d exx, eyy, exy, eyx, dx, dy;
        detail::square_strain(sx, sy, wx, wy, nu, nv, invL, exx, eyy, exy, eyx, dx, dy);
        v4d trace{};
        for (int q = 0; q < 2; ++q)
            for (int r = 0; r < 2; ++r) {
                const v4m some = pw[q][r] > 0;
                trace = some ? v4d(trace + pw[q][r] * pt[q][r]) : trace;
            }
        const v4d half_change = 0.5 * (trace - (exx + eyy));
        exx += half_change; eyy += half_change;
        if (half) { exx *= 0.5; eyy *= 0.5; exy *= 0.5; eyx *= 0.5; }
        // smooth_stress with Trial: eq. 5f, the volume, eq. 6's elastic trial
        v4d rc, rs, sxx, syy, sxy, szz, vol;
        jaumann_rotation(v4d(0.5 * (eyx - exy)), rc, rs);  // eq. 5f (StrainIncrement::theta)
        detail::load(p_.vol.data() + k, vol);
        vol *= 1 + exx + eyy;
        detail::load(p_.sxx.data() + k, sxx); detail::load(p_.syy.data() + k, syy);
        detail::load(p_.sxy.data() + k, sxy); detail::load(p_.szz.data() + k, szz);
        struct { v4d xx, yy, xy, zz; } de;
        elastic_change(mc, exx, eyy, exy, eyx, de.xx, de.yy, de.xy, de.zz);
        elastic_trial(sxx, syy, sxy, szz, de, rc, rs);  // eq. 6
        detail::store(p_.sxx.data() + k, sxx); detail::store(p_.syy.data() + k, syy);
        detail::store(p_.sxy.data() + k, sxy); detail::store(p_.szz.data() + k, szz);
        detail::store(p_.vol.data() + k, vol);
        if constexpr (Move) {  // MOTION BILINEAR: the mean of the increments over the square
            v4d x0, y0;
            detail::load(p_.x.data() + k, x0); detail::load(p_.y.data() + k, y0);
            v4d x = x0 + dx, y = y0 + dy;
            for (int l = 0; l < 4; ++l) {
                const int c = p_.cell[std::size_t(k + l)];
                if (fixed_edges_[std::size_t(c)]) {
                    double xl = x[l], yl = y[l];
                    stop_at_edges(c, x0[l], y0[l], xl, yl);
                    x[l] = xl; y[l] = yl;
                }
            }
            detail::store(p_.x.data() + k, x); detail::store(p_.y.data() + k, y);
        }
    }
    for (; k < b1; ++k) one(k);
}
#endif

// The point loop of the fast kernel, for points k0 .. k1-1 of a chunk, in parts:
//   runs          the scalar loop: runs of points sharing a cell (run_trial: eq. 6 and the
//                 volume; run_motion: eq. 7a/7b, the edge stop, eq. 7 and 8)
//   usual_runs    the AVX2 loop of an elastic scene: fours of one cell that stay in it
//   mohr_blocks   the AVX2 loop of a scene with a Mohr-Coulomb material: blocks of points,
//                 four at a time across cells (move_block), consulted in lanes
//                 (consult_block), then added to their cells (land_block)
// Each is the reference's point pass (reference_points) in another order of work: the same
// functions on the same values (elastic_trial for eq. 6, gather_mean for eq. 7a/7b's
// nodes, stop_at_edges for the impermeable edges), every cell sum taking its terms in
// point order, so the output is the same bit for bit.
//
// The loop's locals, shared by its parts: the chunk's landing and part (copies, kept in
// registers: stores through the cell arrays could alias a reference), and local pointers
// (stores through a double* may alias any double member, which would make the compiler
// reload every member after every store).
struct Simulation::Loop {
    Landing t;
    Part pt;
    // The cells this chunk adds to directly (all of them in the serial pass); a point
    // landing in any other is listed (advance_parted).
    int own_lo;
    unsigned own_n;
    double *px, *py, *psxx, *psyy, *psxy, *pszz, *pvol;
    std::int32_t* pcell;
    const std::uint16_t* pgroup;
    // ADVECT POINTS with threads: each point's increment and the cell it left.
    double *carry_dx, *carry_dy;
    std::int32_t* carry_from;
    int mx, my;
    double L, invL, X, Y;
    bool single;  // one group in the scene
    long k1;
    const Span *cols, *rows;
    const MaterialConstants* const* gconsts;
    const std::uint8_t* fixed;  // fixed_edges_
    int cprev = -2, iprev = -2, jprev = -2;
    // The runs of one block of mohr_blocks' run-by-run form, as its trial stage found them,
    // for its motion stage (a block of kConsultBlock points, extended to the end of a run,
    // holds at most kConsultBlock runs). On the stack: no allocation.
    struct Run { long kend; int c, ci, cj; bool one_group; };
    Run block_runs[kConsultBlock];
    int nrun = 0, irun = 0;
    long consulted = 0;  // Mohr-Coulomb points consulted (profiling)

    LPFDM_INLINE bool owned(int c) const { return unsigned(c) - unsigned(own_lo) < own_n; }
    // Cell c's column ci and row cj; the next cell of the row (the usual case) without an
    // integer division.
    LPFDM_INLINE void locate(int c, int& ci, int& cj) {
        const bool next = c == cprev + 1 && iprev + 1 < mx;
        ci = next ? iprev + 1 : c % mx; cj = next ? jprev : c / mx;
        cprev = c; iprev = ci; jprev = cj;
    }
    // Software prefetch (speed only: no number changes). At a million points the point
    // arrays come from memory at every step, nine streams at once, and the processor's own
    // prefetcher, which follows a stream within a 4 KiB page and starts again at the next,
    // kept the elastic loop waiting for them: the lines of point k + 128 are asked for as it
    // reaches point k (every other four: a line of doubles). The Mohr-Coulomb block loop
    // does not ask: it waits on its arithmetic, not on memory.
    LPFDM_INLINE void ahead(long k) const {
#if defined(__GNUC__)
        constexpr long kAhead = 128;
        if ((k & 4) || k + kAhead >= k1) return;
        const long q = k + kAhead;
        __builtin_prefetch(px + q, 1); __builtin_prefetch(py + q, 1);
        __builtin_prefetch(psxx + q, 1); __builtin_prefetch(psyy + q, 1); __builtin_prefetch(psxy + q, 1);
        __builtin_prefetch(pszz + q, 1); __builtin_prefetch(pvol + q, 1);
        __builtin_prefetch(pcell + q, 1); __builtin_prefetch(pgroup + q, 0);
#else
        (void)k;
#endif
    }
};

// Three builds: Wide false, M = Centre (the default scene, without AVX2) or Default (any
// motion rule and ADVECT POINTS, asked of modes_ as it goes: the options); Wide true
// (MOTION CENTRE without ADVECT POINTS), run by run, or with Blocks in mohr_blocks.
template <Motion M, bool Wide, bool Blocks>
LPFDM_INLINE inline void Simulation::run_points(long k0, long k1, Part& part, Landing& landing) {
    Loop lp;
    lp.t = landing;
    lp.pt = part;
    lp.own_lo = part.own_lo;
    lp.own_n = unsigned(part.own_hi) - unsigned(part.own_lo);
    lp.px = p_.x.data(); lp.py = p_.y.data();
    lp.psxx = p_.sxx.data(); lp.psyy = p_.syy.data(); lp.psxy = p_.sxy.data(); lp.pszz = p_.szz.data();
    lp.pvol = p_.vol.data();
    lp.pcell = p_.cell.data();
    lp.pgroup = p_.group.data();
    lp.carry_dx = p_.carry_dx.empty() ? nullptr : p_.carry_dx.data();
    lp.carry_dy = p_.carry_dy.empty() ? nullptr : p_.carry_dy.data();
    lp.carry_from = p_.carry_from.empty() ? nullptr : p_.carry_from.data();
    lp.mx = mx_; lp.my = my_;
    lp.L = L_; lp.invL = invL_; lp.X = mx_ * L_; lp.Y = my_ * L_;
    lp.single = groups_.size() == 1;
    lp.k1 = k1;
    lp.cols = cols_.data(); lp.rows = rows_.data();
    lp.gconsts = group_consts_.data();
    lp.fixed = fixed_edges_.data();
#if LPFDM_WIDE
    if constexpr (Blocks) mohr_blocks(lp, k0, k1);
#endif
    if constexpr (!Blocks) runs<M, Wide, kWhole>(lp, k0, k1);
    landing = lp.t;
    part = lp.pt;
}

// The runs of points k .. stop-1, in one of three stages (S): kWhole, the whole step of each
// run; kTrial, eq. 6's elastic trial only (a Mohr-Coulomb point is consulted later, by
// consult_block); kMotion, eq. 7a/7b and the landing only (of the runs kTrial found). The
// points are stored cell by cell and mostly stay so (they are created that way, sorted so
// every REORDER steps, and cross a cell edge rarely): a run's cell strain, rotation, nodes
// and elastic increment are read once. Requires p_.cell[k] to be the cell holding
// (x[k], y[k]) (as after every step).
template <Motion M, bool Wide, int S>
LPFDM_INLINE inline void Simulation::runs(Loop& lp, long k, const long stop) {
    while (k < stop) {
#if LPFDM_WIDE
        if constexpr (Wide && S == kWhole) {
            k = usual_runs(lp, k, stop);
            if (k == stop) break;
        }
#endif
        // The run: points k .. kend-1, all in cell c = (ci, cj).
        int c, ci, cj;
        long kend;
        bool one_group = true;
        if constexpr (S == kMotion) {
            const Loop::Run& run = lp.block_runs[lp.irun++];
            c = run.c; ci = run.ci; cj = run.cj; kend = run.kend; one_group = run.one_group;
        } else {
            c = lp.pcell[k];
            lp.locate(c, ci, cj);
            kend = run_end<Wide>(lp, k, stop, c);
            run_trial<Wide>(lp, k, kend, c, one_group);
        }
        if constexpr (S == kTrial) lp.block_runs[lp.nrun++] = Loop::Run{kend, c, ci, cj, one_group};
        if constexpr (S != kTrial) run_motion<M, Wide>(lp, k, kend, c, ci, cj, one_group);
        k = kend;
    }
}

// The end of the run of cell c that starts at point k (the first point after it, at most
// stop).
template <bool Wide>
LPFDM_INLINE inline long Simulation::run_end(const Loop& lp, long k, const long stop, int c) const {
    long kend = k + 1;
#if LPFDM_WIDE
    if constexpr (Wide) {  // four cell numbers per compare: one branch per four points, not one per point
        using detail::v4i;
        using detail::v4f;
        for (; kend + 4 <= stop; kend += 4) {
            v4i w;
            std::memcpy(&w, lp.pcell + kend, sizeof w);
            const int same = __builtin_ia32_movmskps(v4f(w == c));
            if (same != 15) { kend += __builtin_ctz(~unsigned(same)); break; }
        }
        if (kend + 4 > stop)  // the last points only (a scalar loop after every run cost more)
            while (kend < stop && lp.pcell[kend] == c) ++kend;
    }
#endif
    if constexpr (!Wide) while (kend < stop && lp.pcell[kend] == c) ++kend;
    return kend;
}

// eq. 6 with the Jaumann rotation of eq. 5f, then the volume change, for the points k ..
// kend-1 of cell c (a run), by spans of one group: the elastic increment depends on the cell
// and the material only. A Mohr-Coulomb point is consulted here in the scalar loop; in
// the AVX2 loop it keeps its elastic trial for consult_block. one_group: whether the run is
// one span.
template <bool Wide>
LPFDM_INLINE inline void Simulation::run_trial(Loop& lp, long k, const long kend, int c, bool& one_group) {
    double* __restrict psxx = lp.psxx;
    double* __restrict psyy = lp.psyy;
    double* __restrict psxy = lp.psxy;
    double* __restrict pszz = lp.pszz;
    double* __restrict pvol = lp.pvol;
    const std::uint16_t* pgroup = lp.pgroup;
    const CellStrain& ce = strain_[std::size_t(c)];
    const StrainIncrement e{ce.xx, ce.yy, ce.xy, ce.yx};
    const double rc = ce.rc, rs = ce.rs, dv = 1 + e.xx + e.yy;
    for (long q = k; q < kend;) {
        const int g = pgroup[q];
        long qend = lp.single ? kend : q + 1;  // one group in the scene: the whole run
        while (qend < kend && pgroup[qend] == g) ++qend;
        one_group = one_group && qend == kend;
        const MaterialConstants& mc = *group_consts_[std::size_t(g)];
        const Stress de = elastic_change(mc, e);  // eq. 6
        if (mc.model == Model::Elastic || (Wide && mc.model == Model::MohrCoulomb)) {
            long r0 = q;
            q = qend;
#if LPFDM_WIDE
            if constexpr (Wide) {  // four points per register (the simd loop's set-up costs more for runs this short)
                for (; r0 + 4 <= qend; r0 += 4) {
                    detail::v4d xx, yy, xy, zz, vol;
                    detail::load(psxx + r0, xx); detail::load(psyy + r0, yy); detail::load(psxy + r0, xy);
                    detail::load(pszz + r0, zz); detail::load(pvol + r0, vol);
                    elastic_trial(xx, yy, xy, zz, de, rc, rs);
                    vol *= dv;
                    detail::store(psxx + r0, xx); detail::store(psyy + r0, yy); detail::store(psxy + r0, xy);
                    detail::store(pszz + r0, zz); detail::store(pvol + r0, vol);
                }
            }
#endif
            LPFDM_OMP(omp simd)  // independent points: two (or four) per instruction, the same results
            for (long r = r0; r < qend; ++r) {
                double xx = psxx[r], yy = psyy[r], xy = psxy[r], zz = pszz[r];
                elastic_trial(xx, yy, xy, zz, de, rc, rs);
                psxx[r] = xx; psyy[r] = yy; psxy[r] = xy; pszz[r] = zz; pvol[r] *= dv;
            }
        } else if (mc.model == Model::MohrCoulomb) {  // the one-point consult (the AVX2 loop consults in consult_block)
            auto consult = [&](auto own) LPFDM_INLINE {
                for (; q < qend; ++q) {
                    Stress s{psxx[q], psyy[q], psxy[q], pszz[q]};
                    elastic_trial(s.xx, s.yy, s.xy, s.zz, de, rc, rs);  // eq. 6, the elastic trial
                    pvol[q] *= dv;  // before the consult, as everywhere (its plastic work reads V)
                    mohr_consult<decltype(own)::value>(mc, std::size_t(q), pvol[q], s);
                    psxx[q] = s.xx; psyy[q] = s.yy; psxy[q] = s.xy; pszz[q] = s.zz;
                }
            };
            if (modes_.scatter) consult(std::true_type{});  // scatter: each point's own strength
            else consult(std::false_type{});
        } else {
            for (; q < qend; ++q) {
                Stress s{psxx[q], psyy[q], psxy[q], pszz[q]};
                rotate_stress(s, rc, rs);
                user_consult(mc, std::size_t(q), e, s);  // eq. 6 by the user's model
                psxx[q] = s.xx; psyy[q] = s.yy; psxy[q] = s.xy; pszz[q] = s.zz;
                pvol[q] *= dv;
            }
        }
    }
}

// eq. 7a/7b for the points k .. kend-1 of cell c = (ci, cj) (a run), the edge stop, then eq.
// 7 and 8 into the cell each point lands in. The sums of cell c stay in registers while its
// points stay in it.
template <Motion M, bool Wide>
LPFDM_INLINE inline void Simulation::run_motion(Loop& lp, const long k, const long kend, const int c, const int ci, const int cj, const bool one_group) {
    double* __restrict px = lp.px;
    double* __restrict py = lp.py;
    const double* psxx = lp.psxx;
    const double* psyy = lp.psyy;
    const double* psxy = lp.psxy;
    const double* pvol = lp.pvol;
    std::int32_t* pcell = lp.pcell;
    const std::uint16_t* pgroup = lp.pgroup;
    const int mx = lp.mx, my = lp.my;
    const double L = lp.L, invL = lp.invL, X = lp.X, Y = lp.Y;
    Landing& t = lp.t;
    const CellStrain& ce = strain_[std::size_t(c)];
    const StrainIncrement e{ce.xx, ce.yy, ce.xy, ce.yx};
    const std::uint8_t fe = lp.fixed[c];
    // A point of a cell in the last column or row takes the full test below: x < X
    // does not follow from x / L < m there (Span).
    const double xi = lp.cols[ci].at, yj = lp.rows[cj].at;  // ci L, cj L
    const double uc0 = lp.cols[ci].lo, uc1 = lp.cols[ci].hi, vc0 = lp.rows[cj].lo, vc1 = lp.rows[cj].hi;
    const Motion motion = M == Motion::Default ? modes_.motion : M;  // (Default: the options' build)
    const bool carry = M == Motion::Default && modes_.advect == Advect::Points;
    const int n1 = node(ci, cj);
    double ux[4], uy[4], umx = 0, umy = 0;
    gather_nodes(n1, ux, uy);  // eq. 7a/7b's nodes
    if (motion == Motion::Centre) { mean_of_four(ux[0], ux[1], ux[2], ux[3], umx); mean_of_four(uy[0], uy[1], uy[2], uy[3], umy); }
    CellSums sums{0, 0, 0, 0, 0};
    const bool own = lp.owned(c);  // the sums of cell c are this chunk's to add
    if (own) sums = cell_sums(std::size_t(c));
    bool stayed = false;
    int g = one_group ? pgroup[k] : -1;
    double gm = one_group ? groups_[std::size_t(g)].mass : 0, gv0 = one_group ? groups_[std::size_t(g)].vol0 : 0;
    // eq. 7a/7b: where a point of this cell at (x0, y0) moves; one point, or four in the
    // lanes of a vector (the same operations in the same order in every lane). d: the
    // point's own increment (MOTION CENTRE and BILINEAR; ADVECT POINTS carries it).
    auto moved = [&](const auto& x0, const auto& y0, auto& x, auto& y, auto& ddx, auto& ddy) LPFDM_INLINE {
        if (motion == Motion::Centre) move_point_centre(x0, y0, e, xi, yj, L, umx, umy, x, y, ddx, ddy);  // about the centre, with the mean increment
        else if (motion == Motion::Paper) move_point_paper(x0, y0, e, xi, yj, ux[0], uy[0], x, y);        // about node [1]
        else move_point_bilinear(x0, y0, xi, yj, invL, ux, uy, x, y, ddx, ddy);                           // the cell's bilinear field
    };
    // Point q, now at (x, y): its new cell, min(m - 1, int(x / L)) (the run's own cell in
    // the usual case), and eq. 7 and 8 into it.
    auto land = [&](long q, double x, double y, double ddx, double ddy, auto one) LPFDM_INLINE {
        const double u = x * invL, v = y * invL;
        int ni = ci, nj = cj, cn = c;
        if (!(u >= uc0 && u < uc1 && v >= vc0 && v < vc1)) {
            if (!(x >= 0 && x < X && y >= 0 && y < Y)) {  // left the lattice (or not finite): cell_holding's test
                pcell[q] = -1;
                ++t.departed;
                return;
            }
            ni = std::min(mx - 1, int(u)); nj = std::min(my - 1, int(v)); cn = cell(ni, nj);
            pcell[q] = cn;
        }
        if constexpr (!decltype(one)::value) {
            if (pgroup[q] != g) { g = pgroup[q]; gm = groups_[std::size_t(g)].mass; gv0 = groups_[std::size_t(g)].vol0; }
        }
        if (carry) {  // ADVECT POINTS: the increment field the point brings to cell cn
            if (lp.owned(cn)) carry_to(cn, ni, nj, gm, x, y, ddx, ddy, e);
            if (lp.carry_dx) { lp.carry_dx[q] = ddx; lp.carry_dy[q] = ddy; lp.carry_from[q] = c; }  // threads: map_point may add it later
        }
        const double vk = std::min(pvol[q], gv0), sxx = psxx[q], syy = psyy[q], sxy = psxy[q];
        if (cn == c && own) {
            sums.add(gm, vk, sxx, syy, sxy);  // eq. 7, 8
            stayed = true;
        } else {
            if (lp.owned(cn)) add_to_cell(std::size_t(cn), gm, vk, sxx, syy, sxy);  // eq. 7, 8
            else p_.listed[std::size_t(lp.pt.list_at + lp.pt.listed++)] = std::int32_t(q);  // another chunk's cell
            t.cmin = std::min(t.cmin, cn); t.cmax = std::max(t.cmax, cn);
            t.imin = std::min(t.imin, ni); t.imax = std::max(t.imax, ni);
        }
        t.mass += gm;
    };
    // Points q0 .. kend-1 one at a time, in four versions: with or without fixed edges, one
    // group or several.
    auto one_by_one = [&](long q0, auto edges, auto one) LPFDM_INLINE {
        for (long q = q0; q < kend; ++q) {
            const double x0 = px[q], y0 = py[q];
            double x, y, ddx = 0, ddy = 0;
            moved(x0, y0, x, y, ddx, ddy);
            if constexpr (decltype(edges)::value) stop_at_edges(ci, cj, fe, x0, y0, x, y);
            px[q] = x; py[q] = y;
            land(q, x, y, ddx, ddy, one);
        }
    };
    long q0 = k;
#if LPFDM_WIDE
    if constexpr (Wide) {
        // Four points at a time in the lanes of an AVX2 register (one group, no fixed edge):
        // the motion and the test whether each stays in its cell. When all four stay, their
        // sums are added from the lanes in point order; otherwise each lands on its own, in
        // order. Either way the result is that of one_by_one, bit for bit: the same
        // expressions in the same order, and no fused multiply-add (see LPFDM_WIDE).
        static_assert(M == Motion::Centre, "the AVX2 loop follows MOTION CENTRE without ADVECT POINTS");
        if (!fe && one_group && own) {
            using detail::v4d;
            const v4d u0 = {uc0, uc0, uc0, uc0}, u1 = {uc1, uc1, uc1, uc1}, v0 = {vc0, vc0, vc0, vc0}, v1 = {vc1, vc1, vc1, vc1};
            for (; q0 + 4 <= kend; q0 += 4) {
                v4d x0, y0, x, y, ddx{}, ddy{};
                detail::load(px + q0, x0); detail::load(py + q0, y0);
                move_point_centre(x0, y0, e, xi, yj, L, umx, umy, x, y, ddx, ddy);
                detail::store(px + q0, x); detail::store(py + q0, y);
                const v4d u = x * invL, v = y * invL;
                if (!detail::all_lanes((u >= u0) & (u < u1) & (v >= v0) & (v < v1))) {
                    for (int l = 0; l < 4; ++l) land(q0 + l, x[l], y[l], 0.0, 0.0, std::true_type{});
                    continue;
                }
                stayed = true;
                v4d vol, sxx, syy, sxy;
                detail::load(pvol + q0, vol); detail::load(psxx + q0, sxx); detail::load(psyy + q0, syy); detail::load(psxy + q0, sxy);
                sums.add_four(gm, gv0, vol, sxx, syy, sxy, t.mass);  // eq. 7, 8
            }
        }
    }
#endif
    if (fe) one_group ? one_by_one(q0, std::true_type{}, std::true_type{}) : one_by_one(q0, std::true_type{}, std::false_type{});
    else one_group ? one_by_one(q0, std::false_type{}, std::true_type{}) : one_by_one(q0, std::false_type{}, std::false_type{});
    if (stayed) {
        store_sums(std::size_t(c), sums);
        t.cmin = std::min(t.cmin, c); t.cmax = std::max(t.cmax, c);
        t.imin = std::min(t.imin, ci); t.imax = std::max(t.imax, ci);
    }
}

#if LPFDM_WIDE
// The usual run of an elastic scene with 2 x 2 points per cell: four points of one cell (a
// run of four, or the first four of a longer run) of one elastic group, in a cell with no
// fixed edge, that all stay in it. From point k on, such fours one after another, each in
// registers and stored (and added to the cell's sums, eq. 7 and 8) only once all four are
// known to stay. At the first four that is not one, nothing of it is stored and its first
// index is returned, for runs' general code, which makes the same numbers: the same
// expressions in the same order, and a run split in two gives the same sums (they are
// stored and reloaded). This path takes about half the instructions of that code's
// bookkeeping. MOTION CENTRE only (the AVX2 loop's).
LPFDM_INLINE inline long Simulation::usual_runs(Loop& lp, long k, const long stop) {
    using detail::v4d;
    using detail::v4i;
    using detail::v4f;
    double* __restrict px = lp.px;
    double* __restrict py = lp.py;
    double* __restrict psxx = lp.psxx;
    double* __restrict psyy = lp.psyy;
    double* __restrict psxy = lp.psxy;
    double* __restrict pszz = lp.pszz;
    double* __restrict pvol = lp.pvol;
    const std::int32_t* pcell = lp.pcell;
    const std::uint16_t* pgroup = lp.pgroup;
    const double L = lp.L, invL = lp.invL;
    double mass = lp.t.mass;
    int cmin = lp.t.cmin, cmax = lp.t.cmax, imin = lp.t.imin, imax = lp.t.imax;
    for (; k + 4 <= stop; k += 4) {
        lp.ahead(k);
        const int c = pcell[k];
        v4i w;
        std::memcpy(&w, pcell + k, sizeof w);
        if (__builtin_ia32_movmskps(v4f(w == c)) != 15) break;
        const int g = pgroup[k];
        if (!lp.single) {
            std::uint64_t gw;
            std::memcpy(&gw, pgroup + k, sizeof gw);
            if (gw != std::uint64_t(g) * 0x0001000100010001ULL) break;
        }
        const MaterialConstants& mc = *lp.gconsts[g];
        if (mc.model != Model::Elastic || lp.fixed[c] || !lp.owned(c)) break;
        int ci, cj;
        lp.locate(c, ci, cj);
        const CellStrain& ce = strain_[std::size_t(c)];
        const StrainIncrement e{ce.xx, ce.yy, ce.xy, ce.yx};
        const Stress de = elastic_change(mc, e);  // eq. 6
        v4d xx, yy, xy, zz, vol, x0, y0, x, y;
        detail::load(psxx + k, xx); detail::load(psyy + k, yy); detail::load(psxy + k, xy);
        detail::load(pszz + k, zz); detail::load(pvol + k, vol);
        elastic_trial(xx, yy, xy, zz, de, ce.rc, ce.rs);
        vol *= 1 + e.xx + e.yy;
        detail::load(px + k, x0); detail::load(py + k, y0);
        double umx, umy;
        gather_mean(node(ci, cj), umx, umy);  // eq. 7a/7b's nodes
        v4d ddx, ddy;
        move_point_centre(x0, y0, e, lp.cols[ci].at, lp.rows[cj].at, L, umx, umy, x, y, ddx, ddy);  // eq. 7a/7b about the centre
        const double uc0 = lp.cols[ci].lo, uc1 = lp.cols[ci].hi, vc0 = lp.rows[cj].lo, vc1 = lp.rows[cj].hi;
        const v4d u = x * invL, v = y * invL;
        if (!detail::all_lanes((u >= v4d{uc0, uc0, uc0, uc0}) & (u < v4d{uc1, uc1, uc1, uc1}) & (v >= v4d{vc0, vc0, vc0, vc0}) & (v < v4d{vc1, vc1, vc1, vc1}))) break;
        detail::store(psxx + k, xx); detail::store(psyy + k, yy); detail::store(psxy + k, xy);
        detail::store(pszz + k, zz); detail::store(pvol + k, vol);
        detail::store(px + k, x); detail::store(py + k, y);
        CellSums sums = cell_sums(std::size_t(c));
        sums.add_four(groups_[std::size_t(g)].mass, groups_[std::size_t(g)].vol0, vol, xx, yy, xy, mass);  // eq. 7, 8
        store_sums(std::size_t(c), sums);
        cmin = std::min(cmin, c); cmax = std::max(cmax, c);
        imin = std::min(imin, ci); imax = std::max(imax, ci);
    }
    lp.t.mass = mass;
    lp.t.cmin = cmin; lp.t.cmax = cmax; lp.t.imin = imin; lp.t.imax = imax;
    return k;
}

// The AVX2 loop of a scene with a Mohr-Coulomb material (mohr_groups_): the points go in
// blocks of about kConsultBlock, each ending where a run ends: the elastic trial of the
// block's runs, then the consult of its Mohr-Coulomb points four at a time whatever cells
// they lie in (the consult needs no cell; lanes within runs, rarely more than four points
// long with 2 x 2 points per cell, left half the returns to the one-point code), then the
// motion and landing of its runs, which read the consulted stresses while they are still
// in the cache. A scene with no user's model takes blocks of kConsultBlock points (the
// chunk's last one shorter), not ending with a run, four points at a time instead: the
// trial and the motion of the block (move_block; the motion of eq. 7a/7b needs no
// stress), the consult, then the sums of eq. 7 and 8 (land_block). A run split between
// two blocks adds the same sums.
LPFDM_INLINE inline void Simulation::mohr_blocks(Loop& lp, const long k0, const long k1) {
    for (long b0 = k0; b0 < k1;) {
        long b1 = std::min(k1, b0 + kConsultBlock);
        if (no_user_groups_) {  // four points at a time across runs
            move_block(lp, b0, b1);
            consult_timed(lp, b0, b1);
            land_block(lp, b0, b1);
            b0 = b1;  // the next block may start inside a run: a run split in two adds the same sums
            continue;
        }
        while (b1 < k1 && lp.pcell[b1] == lp.pcell[b1 - 1]) ++b1;
        lp.nrun = lp.irun = 0;
        runs<Motion::Centre, true, kTrial>(lp, b0, b1);
        consult_timed(lp, b0, b1);
        runs<Motion::Centre, true, kMotion>(lp, b0, b1);
        b0 = b1;
    }
}

inline long Simulation::consult_points(const PointArrays& a, const long b0, const long b1) {
    long consulted = 0;
    for (long q = b0; q < b1;) {  // spans of points of one material
        const MaterialConstants& mc = *group_consts_[std::size_t(a.group[q])];
        long qend = groups_.size() == 1 ? b1 : q + 1;
        while (qend < b1 && group_consts_[std::size_t(a.group[qend])] == &mc) ++qend;
        if (mc.model == Model::MohrCoulomb) {
            if (modes_.scatter) consult_lanes<true>(mc, q, qend, a);  // scatter: each point's own strength
            else consult_lanes<false>(mc, q, qend, a);
            consulted += qend - q;
        }
        q = qend;
    }
    return consulted;
}
inline long Simulation::consult_points(const long b0, const long b1) {
    return consult_points(PointArrays{p_.sxx.data(), p_.syy.data(), p_.sxy.data(), p_.szz.data(), p_.vol.data(), p_.group.data()}, b0, b1);
}

// consult_points, timed when profiling (two clock reads a block of about 256 points).
LPFDM_INLINE inline void Simulation::consult_timed(Loop& lp, const long b0, const long b1) {
    auto consult_block = [&]() LPFDM_INLINE { lp.consulted += consult_points(PointArrays{lp.psxx, lp.psyy, lp.psxy, lp.pszz, lp.pvol, lp.pgroup}, b0, b1); };
    if (profiling_) {
        const auto c0 = std::chrono::steady_clock::now();
        lp.consulted = 0;
        consult_block();
        lp.pt.return_seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - c0).count();
        lp.pt.returned += lp.consulted;
    } else {
        consult_block();
    }
}

// The block's first pass, four points at a time whatever cells they lie in: eq. 6's
// elastic trial and the volume change (Hooke's law for an elastic or a Mohr-Coulomb point;
// the latter is consulted afterwards), then eq. 7a/7b (MOTION CENTRE, which needs no
// stress) and the cell each point lands in, written to its cell (-1: it left the lattice),
// with the box of those cells and the mass landed. Each four's strain records and nodal
// increments, gathered into the lanes once for both (read once when the four share a
// cell). A flowing scene leaves runs of one or two points in a cell, and the run-by-run
// loop then mispredicts about one branch per point (where a run ends); this one
// branches on what is rare (a cell with a fixed edge or near a wall, whose points
// stop_at_edges holds one by one; a point leaving the lattice; four points of two
// materials) and on whether the four share a cell. The sums of eq. 7 and 8 wait for the
// consulted stresses (land_block).
LPFDM_INLINE inline void Simulation::move_block(Loop& lp, long b0, const long b1) {
    using detail::v4d;
    using detail::v4i;
    using detail::v4f;
    double* __restrict px = lp.px;
    double* __restrict py = lp.py;
    double* __restrict psxx = lp.psxx;
    double* __restrict psyy = lp.psyy;
    double* __restrict psxy = lp.psxy;
    double* __restrict pszz = lp.pszz;
    double* __restrict pvol = lp.pvol;
    std::int32_t* pcell = lp.pcell;
    const std::uint16_t* pgroup = lp.pgroup;
    const int mx = lp.mx, my = lp.my;
    const double L = lp.L, invL = lp.invL, X = lp.X, Y = lp.Y;
    const double inv_mx = 1.0 / mx;
    const MaterialConstants* const* gconsts = lp.gconsts;
    const std::uint8_t* fixed = lp.fixed;
    const bool single = lp.single;
    Landing t = lp.t;  // a local: kept in registers
    // The column and row of the cells c in the lanes: c / mx as the truncated double
    // (c + 0.5) / mx, exact for every int c (the quotient lies at least 0.5 / mx from an
    // integer, its rounding error below (c + 0.5) / mx 2^-52).
    auto columns_rows = [&](const v4i& c, v4i& ci, v4i& cj) LPFDM_INLINE {
        cj = __builtin_convertvector((__builtin_convertvector(c, v4d) + 0.5) * inv_mx, v4i);
        ci = c - cj * mx;
    };
    // Four cells in the lanes, all the same one.
    auto one_cell = [](const v4i& c) LPFDM_INLINE { return __builtin_ia32_movmskps(v4f(c == c[0])) == 15; };
    // eq. 6's trial and the volume change of one point, or of four in lanes, of material mc.
    auto trial = [&](const MaterialConstants& mc, auto& xx, auto& yy, auto& xy, auto& zz, auto& vol, const auto& e, const auto& rc, const auto& rs) LPFDM_INLINE {
        using V = std::remove_reference_t<decltype(xx)>;  // one value or four lanes
        struct { V xx, yy, xy, zz; } de;
        elastic_change(mc, e.xx, e.yy, e.xy, e.yx, de.xx, de.yy, de.xy, de.zz);  // eq. 6
        elastic_trial(xx, yy, xy, zz, de, rc, rs);
        vol *= 1.0 + e.xx + e.yy;
    };
    auto trial_one = [&](long q) LPFDM_INLINE {
        const CellStrain& ce = strain_[std::size_t(pcell[q])];
        trial(*gconsts[pgroup[q]], psxx[q], psyy[q], psxy[q], pszz[q], pvol[q], ce, ce.rc, ce.rs);
    };
    auto landed_in = [&](int cn, int ni) LPFDM_INLINE {  // the box of the cells landed in
        t.cmin = std::min(t.cmin, cn); t.cmax = std::max(t.cmax, cn);
        t.imin = std::min(t.imin, ni); t.imax = std::max(t.imax, ni);
    };
    // Point q, moved to (x, y): the cell it lands in (cell_holding), or it left.
    auto land_one = [&](long q, double x, double y) LPFDM_INLINE {
        const int cn = cell_holding(x, y);
        pcell[q] = cn;
        if (cn < 0) { ++t.departed; return; }  // left the lattice (or not finite)
        landed_in(cn, cn % mx);
        t.mass += groups_[pgroup[q]].mass;
    };
    for (; b0 + 4 <= b1; b0 += 4) {
        v4i c, ci, cj;
        std::memcpy(&c, pcell + b0, sizeof c);
        const bool one = one_cell(c);
        v4d rc, rs;
        const detail::StrainLanes e = strain_lanes(c, one, rc, rs);
        int g;
        const bool one_group = one_group_of_four(pgroup, single, b0, g);
        if (one_group) {
            v4d xx, yy, xy, zz, vol;
            detail::load(psxx + b0, xx); detail::load(psyy + b0, yy); detail::load(psxy + b0, xy);
            detail::load(pszz + b0, zz); detail::load(pvol + b0, vol);
            trial(*gconsts[g], xx, yy, xy, zz, vol, e, rc, rs);
            detail::store(psxx + b0, xx); detail::store(psyy + b0, yy); detail::store(psxy + b0, xy);
            detail::store(pszz + b0, zz); detail::store(pvol + b0, vol);
        } else {  // points of two materials
            for (int l = 0; l < 4; ++l) trial_one(b0 + l);
        }
        columns_rows(c, ci, cj);
        const v4i n1 = cj * (mx + 1) + ci;  // node(ci, cj)
        v4d umx, umy;
        if (one) {
            double mean_x, mean_y;
            gather_mean(n1[0], mean_x, mean_y);  // eq. 7a/7b's nodes
            umx = v4d{mean_x, mean_x, mean_x, mean_x}; umy = v4d{mean_y, mean_y, mean_y, mean_y};
        } else {
            gather_mean(n1, umx, umy);  // eq. 7a/7b's nodes, of four cells
        }
        const v4d xi = __builtin_convertvector(ci, v4d) * L, yj = __builtin_convertvector(cj, v4d) * L;  // ci L, cj L
        v4d x0, y0, x, y, ddx, ddy;
        detail::load(px + b0, x0); detail::load(py + b0, y0);
        move_point_centre(x0, y0, e, xi, yj, L, umx, umy, x, y, ddx, ddy);  // eq. 7a/7b
        if (fixed[c[0]] | fixed[c[1]] | fixed[c[2]] | fixed[c[3]]) {  // a cell with a fixed edge, or near a wall
            for (int l = 0; l < 4; ++l) {
                if (!fixed[c[l]]) continue;
                double xl = x[l], yl = y[l];
                stop_at_edges(c[l], x0[l], y0[l], xl, yl);
                x[l] = xl; y[l] = yl;
            }
        }
        detail::store(px + b0, x); detail::store(py + b0, y);
        if (!detail::all_lanes((x >= 0) & (x < X) & (y >= 0) & (y < Y))) {  // a point left the lattice
            for (int l = 0; l < 4; ++l) land_one(b0 + l, x[l], y[l]);
            continue;
        }
        const v4i mx1 = {mx - 1, mx - 1, mx - 1, mx - 1}, my1 = {my - 1, my - 1, my - 1, my - 1};
        v4i ni = __builtin_convertvector(x * invL, v4i), nj = __builtin_convertvector(y * invL, v4i);
        ni = ni < mx1 ? ni : mx1; nj = nj < my1 ? nj : my1;  // std::min(m - 1, int(x / L))
        const v4i cn = nj * mx + ni;  // cell(ni, nj)
        std::memcpy(pcell + b0, &cn, sizeof cn);
        if (one_cell(cn)) {
            landed_in(cn[0], ni[0]);
        } else {
            for (int l = 0; l < 4; ++l) landed_in(cn[l], ni[l]);
        }
        if (one_group) {
            const double gm = groups_[std::size_t(g)].mass;
            for (int l = 0; l < 4; ++l) t.mass += gm;
        } else {
            for (int l = 0; l < 4; ++l) t.mass += groups_[pgroup[b0 + l]].mass;
        }
    }
    for (; b0 < b1; ++b0) {  // the last one to three points of the chunk: the reference's steps
        trial_one(b0);
        const int c = pcell[b0];
        const CellStrain& ce = strain_[std::size_t(c)];
        const double x0 = px[b0], y0 = py[b0];
        double x, y, ddx, ddy;
        move_with_cell(c % mx, c / mx, StrainIncrement{ce.xx, ce.yy, ce.xy, ce.yx}, x0, y0, x, y, ddx, ddy);  // eq. 7a/7b
        stop_at_edges(c, x0, y0, x, y);
        px[b0] = x; py[b0] = y;
        land_one(b0, x, y);
    }
    lp.t = t;
}

// The block's last pass: eq. 7 and 8, each point (not departed) added to the sums of the
// cell it landed in, in point order, or listed when that cell is another chunk's.
LPFDM_INLINE inline void Simulation::land_block(Loop& lp, long b0, const long b1) {
    using detail::v4d;
    using detail::v4i;
    using detail::v4f;
    const double* pvol = lp.pvol;
    const double* psxx = lp.psxx;
    const double* psyy = lp.psyy;
    const double* psxy = lp.psxy;
    const std::int32_t* pcell = lp.pcell;
    const std::uint16_t* pgroup = lp.pgroup;
    const int own_lo = lp.own_lo;
    const unsigned own_n = lp.own_n;
    auto owned = [&](int c) LPFDM_INLINE { return unsigned(c) - unsigned(own_lo) < own_n; };  // Loop::owned
    auto deposit = [&](long q, int cn) LPFDM_INLINE {
        if (cn < 0) return;  // left the lattice
        const Group& gr = groups_[pgroup[q]];
        if (owned(cn)) add_to_cell(std::size_t(cn), gr.mass, std::min(pvol[q], gr.vol0), psxx[q], psyy[q], psxy[q]);  // eq. 7, 8
        else p_.listed[std::size_t(lp.pt.list_at + lp.pt.listed++)] = std::int32_t(q);  // another chunk's cell
    };
    for (; b0 + 4 <= b1; b0 += 4) {
        v4i cn;
        std::memcpy(&cn, pcell + b0, sizeof cn);
        int g;
        if (__builtin_ia32_movmskps(v4f(cn == cn[0])) == 15 && owned(cn[0]) && one_group_of_four(pgroup, lp.single, b0, g)) {
            // all four in one cell (the usual case while runs are long): its sums in
            // registers, the four added in point order as deposit() adds them
            v4d vol, sxx, syy, sxy;
            detail::load(pvol + b0, vol); detail::load(psxx + b0, sxx); detail::load(psyy + b0, syy); detail::load(psxy + b0, sxy);
            CellSums sums = cell_sums(std::size_t(cn[0]));
            double landed = 0;  // (move_block counted the mass landed)
            sums.add_four(groups_[std::size_t(g)].mass, groups_[std::size_t(g)].vol0, vol, sxx, syy, sxy, landed);  // eq. 7, 8
            store_sums(std::size_t(cn[0]), sums);
            continue;
        }
        for (int l = 0; l < 4; ++l) deposit(b0 + l, cn[l]);
    }
    for (; b0 < b1; ++b0) deposit(b0, pcell[b0]);
}

// Four points q .. q+3 of one group g (read into g): their groups as one 64-bit word.
LPFDM_INLINE inline bool Simulation::one_group_of_four(const std::uint16_t* pgroup, bool single, long q, int& g) {
    g = pgroup[q];
    if (single) return true;
    std::uint64_t gw;
    std::memcpy(&gw, pgroup + q, sizeof gw);
    return gw == std::uint64_t(g) * 0x0001000100010001ULL;
}

// The strain records (e) and rotations (rc, rs) of the cells c of four points in the lanes;
// one: the four share a cell, read once.
LPFDM_INLINE inline detail::StrainLanes Simulation::strain_lanes(const detail::v4i& c, bool one, detail::v4d& rc, detail::v4d& rs) const {
    const CellStrain* sc = strain_.data();
    if (one) {
        const CellStrain& ce = sc[c[0]];
        rc = detail::v4d{ce.rc, ce.rc, ce.rc, ce.rc}; rs = detail::v4d{ce.rs, ce.rs, ce.rs, ce.rs};
        return detail::StrainLanes{{ce.xx, ce.xx, ce.xx, ce.xx}, {ce.yy, ce.yy, ce.yy, ce.yy}, {ce.xy, ce.xy, ce.xy, ce.xy}, {ce.yx, ce.yx, ce.yx, ce.yx}};
    }
    const CellStrain &s0 = sc[c[0]], &s1 = sc[c[1]], &s2 = sc[c[2]], &s3 = sc[c[3]];
    rc = detail::v4d{s0.rc, s1.rc, s2.rc, s3.rc}; rs = detail::v4d{s0.rs, s1.rs, s2.rs, s3.rs};
    return detail::StrainLanes{{s0.xx, s1.xx, s2.xx, s3.xx}, {s0.yy, s1.yy, s2.yy, s3.yy}, {s0.xy, s1.xy, s2.xy, s3.xy}, {s0.yx, s1.yx, s2.yx, s3.yx}};
}
#endif

// eq. 7 and 8 for point k, into the cell it lies in; with ADVECT POINTS also the
// increment field it brings there.
inline void Simulation::map_point(std::size_t k) {
    const int c = p_.cell[k];
    const Group& g = groups_[p_.group[k]];
    const double m = g.mass, v = std::min(p_.vol[k], g.vol0);
    add_to_cell(std::size_t(c), m, v, p_.sxx[k], p_.syy[k], p_.sxy[k]);  // eq. 7, 8
    if (modes_.advect == Advect::Points && !p_.carry_dx.empty()) {  // (the carry arrays: with threads only)
        const int f = p_.carry_from[k];
        carry_to(c, c % mx_, c / mx_, m, p_.x[k], p_.y[k], p_.carry_dx[k], p_.carry_dy[k], {strain_[f].xx, strain_[f].yy, strain_[f].xy, strain_[f].yx});
    }
}

// map_to_lattice: eq. 7 and 8 for every point, in point order, into the cell it lies in
// (after set-up, after a program moved points, or when advance_parted's chunks clashed).
LPFDM_DEF void Simulation::map_points() {
    if (modes_.mapping == Mapping::Smooth) {  // every cell each point's square overlaps (the reference's mapping)
        for (auto* v : {&cmass_, &cvol_, &svxx_, &svyy_, &svxy_, &shx_, &shy_, &smu_, &smv_}) std::fill(v->begin(), v->end(), 0.0);
        Landing t;
        smooth_map(t);
        occupied_ = landed(t);
        parts_known_ = false;
        return;
    }
    clear_cells();
    Landing t;
    for (std::size_t k = 0; k < p_.size(); ++k) {
        map_point(k);
        const int c = p_.cell[k];
        t.cmin = std::min(t.cmin, c); t.cmax = std::max(t.cmax, c);
        const int i = p_.x[k] >= 0 ? std::min(mx_ - 1, int(p_.x[k] * invL_)) : c % mx_;
        t.imin = std::min(t.imin, i); t.imax = std::max(t.imax, i);
        t.mass += groups_[p_.group[k]].mass;
    }
    parts_known_ = false;  // not advance_parted's chunks
    mass_in_ = t.mass;
    occupied_ = landed(t);
}

// Net nodal force: each node gathers from its (up to) four cells, eq. 9 replaced by
// the virtual-work transpose of eq. 5, then gravity on the lumped mass, eq. 10. A
// node gathers rather than cells scattering, so the sum has one fixed order.
LPFDM_DEF void Simulation::nodal_forces() {
    const Range nr{occupied_.i0, occupied_.empty() ? 0 : occupied_.i1 + 1, occupied_.j0, occupied_.empty() ? 0 : occupied_.j1 + 1};
    const double inv2L = 0.5 * invL_, L2 = L_ * L_;
    const Range keep = nr.grow(1, mx_ + 1, my_ + 1);  // compensate() asks which nodes are new
    const int mx = mx_, my = my_;
    double *sxx = svxx_.data(), *syy = svyy_.data(), *sxy = svxy_.data();
    const double* cm = cmass_.data();
    const double* cv = cvol_.data();
    double *nm = nmass_.data(), *nm_prev = nmass_prev_.data(), *fxn = fx_.data(), *fyn = fy_.data();
    std::uint8_t* row_gained = row_gained_.data();
    const double gx = sc_.gravity_x, gy = sc_.gravity_y;
    // Only eq. 12 reads the previous masses: the nodes of nr keep theirs as the forces'
    // loop below overwrites them, and it notes the rows where a node gained mass
    // (compensate() visits only those); here the ring of keep around nr.
    const bool keep_prev = modes_.advect != Advect::Points;
    if (keep_prev) {
        auto copy = [&](int j, int i0, int i1) { std::copy(nm + (j * (mx + 1) + i0), nm + (j * (mx + 1) + i1), nm_prev + (j * (mx + 1) + i0)); };
        for (int j = keep.j0; j < keep.j1; ++j) {
            if (j < nr.j0 || j >= nr.j1) { copy(j, keep.i0, keep.i1); continue; }
            copy(j, keep.i0, nr.i0);
            copy(j, nr.i1, keep.i1);
        }
    }
    // eq. 8 with the fill capped at one, applied once per cell (map_to_lattice clears it);
    // cell c, or the cells c .. c + 3 in the lanes of a vector T.
    const Range oc = occupied_;
    auto smear = [&](int c, auto tag) LPFDM_INLINE {
        using T = typename decltype(tag)::type;
        T v, xx, yy, xy;
        detail::load(cv + c, v); detail::load(sxx + c, xx); detail::load(syy + c, yy); detail::load(sxy + c, xy);
        T w;
        smear_weight(v, L2, inv2L, w);  // eq. 8
        detail::store(sxx + c, xx * w); detail::store(syy + c, yy * w); detail::store(sxy + c, xy * w);
    };
    auto smear_row = [&](int j, auto wide) LPFDM_INLINE { detail::sweep(j * mx + oc.i0, j * mx + oc.i1, wide, smear); };
    by_rows(kSmearRows, oc.j0, oc.j1, oc.size(), [&](int j) { each_row(smear_row, j); });
    const bool smooth = modes_.mapping == Mapping::Smooth;
    if (smooth)  // MAPPING SMOOTH: the moments as reference_nodal_forces makes them
        for (int j = oc.j0; j < oc.j1; ++j)
            for (int c = j * mx + oc.i0; c < j * mx + oc.i1; ++c) smooth_moment(std::size_t(c));
    const bool hourglass = modes_.hourglass;
    const double khg = hourglass ? sc_.hourglass * 0.25 / (sc_.dt_s * sc_.dt_s) : 0.0;
    // The node is corner [1] of cell (i, j), [2] of (i-1, j), [3] of (i, j-1) and [4] of
    // (i-1, j-1); with b = (+-1, +-1)/2L the transpose of eq. 5 gives the signs below (X,
    // Y, S = sum V sigma_xx, _yy, _xy, already divided by 2L). Cells outside the lattice
    // count as empty; empty cells hold zeros.
    // Interior: a node with all four cells, no HOURGLASS and no MAPPING SMOOTH, where the
    // tests are known true at compile time (the same sums in the same order).
    // T: node (i, j), or (interior only) the nodes i .. i + 3 in the lanes of a vector.
    auto node_force = [&](int i, int j, auto interior, auto tag, bool& gained) LPFDM_INLINE {
        using T = typename decltype(tag)::type;
        constexpr bool in = decltype(interior)::value;
        T fx{}, fy{}, m{};
        const bool left = in || i > 0, right = in || i < mx, below = in || j > 0, above = in || j < my;
        const int c = j * mx + i;  // cell (i, j)
        // The stresses and mass of cell a.
        T xx, yy, xy, ma;
        auto at = [&](int a) LPFDM_INLINE { detail::load(sxx + a, xx); detail::load(syy + a, yy); detail::load(sxy + a, xy); detail::load(cm + a, ma); };
        if (right && above) { at(c); add_cell_force<1>(xx, yy, xy, fx, fy); m += ma; }
        if (left && above) { at(c - 1); add_cell_force<2>(xx, yy, xy, fx, fy); m += ma; }
        if (right && below) { at(c - mx); add_cell_force<3>(xx, yy, xy, fx, fy); m += ma; }
        if (left && below) { at(c - mx - 1); add_cell_force<4>(xx, yy, xy, fx, fy); m += ma; }
        // A node taken one value at a time (every node, with either option): MAPPING
        // SMOOTH's moments, then HOURGLASS's viscous force on the zero-energy mode, by the
        // functions reference_nodal_forces calls, in its order (the other order differed
        // in the last bit where both are on).
        if constexpr (!in) if (smooth) smooth_node_force(c, right, left, above, below, fx, fy);
        if constexpr (!in) if (hourglass) hourglass_node_force(c, right, left, above, below, khg, fx, fy);
        const int n = j * (mx + 1) + i;
        const T mn = 0.25 * m;  // eq. 10: 1/4 of the connected cells' masses
        if (keep_prev) {
            T was;
            detail::load(nm + n, was);
            detail::store(nm_prev + n, was);
            // gained_mass, in the lanes of a vector or not.
            if constexpr (std::is_same_v<T, double>) {
                gained = gained || gained_mass(was, mn);
            } else {
#if LPFDM_WIDE
                const T zero{};
                gained = gained || !detail::all_lanes((was > zero) | (mn == zero));
#endif
            }
        }
        detail::store(nm + n, mn);
        detail::store(fxn + n, fx + gx * mn);
        detail::store(fyn + n, fy + gy * mn);
    };
    const detail::Tag<double> one;
    auto force_row = [&](int j, auto wide) LPFDM_INLINE {
        const bool inner_row = j > 0 && j < my && !hourglass && !smooth;
        const int ia = inner_row ? std::min(std::max(nr.i0, 1), nr.i1) : nr.i1, ib = inner_row ? std::max(ia, std::min(nr.i1, mx)) : nr.i1;
        bool gained = false;
        for (int i = nr.i0; i < ia; ++i) node_force(i, j, std::false_type{}, one, gained);
        detail::sweep(ia, ib, wide, [&](int i, auto tag) LPFDM_INLINE { node_force(i, j, std::true_type{}, tag, gained); });
        for (int i = ib; i < nr.i1; ++i) node_force(i, j, std::false_type{}, one, gained);
        row_gained[j] = gained;
    };
    by_rows(kForceRows, nr.j0, nr.j1, nr.size(), [&](int j) { each_row(force_row, j); });
}

// eq. 12: the increment carried by node k belonged to the material now at x_k - du_k;
// correct it with the strain increments of the cell found there.
LPFDM_DEF void Simulation::compensate() {
    const Range nr{occupied_.i0, occupied_.empty() ? 0 : occupied_.i1 + 1, occupied_.j0, occupied_.empty() ? 0 : occupied_.j1 + 1};
    if (modes_.advect == Advect::Flip) return;  // its transfer came in the points' phase
    if (modes_.advect == Advect::Points) { carried_increments(nr); return; }
    // Nodes that gained mass this step take the mean increment of their neighbours that
    // had mass (read before those are compensated, so the order does not matter); only
    // rows where nodal_forces() saw such a node.
    long gaining = 0;
    for (int j = nr.j0; j < nr.j1; ++j) gaining += row_gained_[std::size_t(j)];
    const int mx = mx_, my = my_;
    const double invL = invL_;
    const Range st = strained_;
    double *ux_n = dux_.data(), *uy_n = duy_.data();
    const double* nm = nmass_.data();
    const double* nm_prev = nmass_prev_.data();
    [[maybe_unused]] const CellStrain* cs = strain_.data();  // the AVX2 lanes read it
    if (gaining) by_rows(kFillRows, nr.j0, nr.j1, gaining * (nr.i1 - nr.i0), [&](int j) {
        if (!row_gained_[std::size_t(j)]) return;
        for (int i = nr.i0; i < nr.i1; ++i) {
            const int n = j * (mx + 1) + i;
            if (!gained_mass(nm_prev[n], nm[n])) continue;
            double sx = 0, sy = 0, msum = 0;
            for (int qj = std::max(0, j - 1); qj <= std::min(my, j + 1); ++qj)
                for (int qi = std::max(0, i - 1); qi <= std::min(mx, i + 1); ++qi) {
                    const int q = qj * (mx + 1) + qi;
                    const double mq = nm_prev[q];
                    if (mq > 0) { sx += mq * ux_n[q]; sy += mq * uy_n[q]; msum += mq; }
                }
            if (msum > 0) { ux_n[n] = sx / msum; uy_n[n] = sy / msum; }
        }
    });
    // Node (i, j): eq. 12 one node at a time, as the reference does it.
    auto shift = [&](int i, int j) LPFDM_INLINE {
        const int n = j * (mx + 1) + i;
        double ux = ux_n[n], uy = uy_n[n], exx, eyy, exy, eyx;
        if ((ux == 0 && uy == 0) || nm_prev[n] == 0) return;
        if (!strain_at(i - ux * invL, j - uy * invL, st, exx, eyy, exy, eyx)) return;
        compensate_increment(ux, uy, exx, eyy, exy, eyx);  // eq. 12a, 12b
        ux_n[n] = ux; uy_n[n] = uy;
    };
    // Nodes i .. i + 3 of row j in the lanes of a vector, when each lane is one that shift
    // leaves alone or one whose x_node - du_node lies in a strained cell, or on the edge of
    // two or four strained cells: strain_at's two first cases and compensate_increment,
    // restated in lanes, the same operations on the same numbers. Otherwise (the
    // border of the strained box, a number not finite) the four nodes go one at a time.
    auto shift_row = [&](int j, auto wide) LPFDM_INLINE {
        [[maybe_unused]] const bool below_ok = j > st.j0 && j < st.j1;  // rows j - 1 and j of cells strained
        detail::sweep(nr.i0, nr.i1, wide, [&](int i, auto tag) LPFDM_INLINE {
            using T = typename decltype(tag)::type;
            if constexpr (std::is_same_v<T, double>) {
                shift(i, j);
            } else {
#if LPFDM_WIDE
                using detail::v4d;
                using detail::v4m;
                using detail::v4i;
                const int n = j * (mx + 1) + i;
                v4d ux, uy, mp;
                detail::load(ux_n + n, ux); detail::load(uy_n + n, uy); detail::load(nm_prev + n, mp);
                const v4d zero{};
                const v4m idle = ((ux == zero) & (uy == zero)) | (mp == zero);
                if (detail::all_lanes(idle)) return;
                auto compensate_lanes = [&](const v4d& exx, const v4d& eyy, const v4d& exy, const v4d& eyx) LPFDM_INLINE {
                    v4d sx = ux, sy = uy;
                    compensate_increment(sx, sy, exx, eyy, exy, eyx);  // eq. 12a, 12b
                    detail::store(ux_n + n, idle ? ux : sx);
                    detail::store(uy_n + n, idle ? uy : sy);
                };
                const v4d X = double(i) + v4d{0, 1, 2, 3}, Y = zero + double(j);  // i + l is exact
                const v4d fxs = X - ux * invL, fys = Y - uy * invL;
                // Each lane's cell (ci0, cj0) as strain_at finds it, as an index into the
                // strains, and whether x_node - du_node lies on a vertical (hx) or horizontal
                // (hy) cell edge, where the mean of that cell and the next takes its place.
                int at[4];
                v4m hx, hy;
                const v4d h = zero + 0.5;
                if (i > st.i0 && i + 4 <= st.i1 && below_ok &&
                    detail::all_lanes(idle | ((fxs > X - h) & (fxs < X + h) & (fys > Y - h) & (fys < Y + h)))) {
                    // The usual group: each moving lane's x_node - du_node within half a cell
                    // of its node, so in or on the edges of the node's four cells, and those
                    // strained for every lane (the box tested once). strain_at's floor is then
                    // one comparison: cell (i + l - 1, j - 1), one to the right where fxs > i + l,
                    // one up where fys > j. (An idle lane takes one of those cells too.)
                    const int right = detail::lane_bits(fxs > X), up = detail::lane_bits(fys > Y);
                    const int c00 = (j - 1) * mx + i - 1;
                    auto cell_of = [&](int l) LPFDM_INLINE { return c00 + l + ((right >> l) & 1) + ((up >> l) & 1) * mx; };
                    hx = fxs == X; hy = fys == Y;
                    if (detail::none_of_lanes((hx | hy) & ~idle)) {  // one cell a lane: no mean to take
                        v4d r0, r1, r2, r3;
                        detail::load(&cs[cell_of(0)].xx, r0); detail::load(&cs[cell_of(1)].xx, r1);
                        detail::load(&cs[cell_of(2)].xx, r2); detail::load(&cs[cell_of(3)].xx, r3);
                        v4d exx, eyy, exy, eyx;
                        detail::transpose_strains(r0, r1, r2, r3, exx, eyy, exy, eyx);
                        compensate_lanes(exx, eyy, exy, eyx);
                        return;
                    }
                    for (int l = 0; l < 4; ++l) at[l] = cell_of(l);
                } else {
                    // The floor as shift takes it: int() truncates (as the conversion of the lanes
                    // does), then one less below a negative number that is not whole.
                    const v4d tx = __builtin_convertvector(__builtin_convertvector(fxs, v4i), v4d);
                    const v4d ty = __builtin_convertvector(__builtin_convertvector(fys, v4i), v4d);
                    const v4d one = zero + 1, ci = fxs < tx ? tx - one : tx, cj = fys < ty ? ty - one : ty;
                    // On an edge (fxs or fys whole), the cell below or to the left as well.
                    hx = fxs == ci; hy = fys == cj;
                    const v4d ci0 = hx ? ci - one : ci, cj0 = hy ? cj - one : cj;
                    const v4m strained = (ci0 >= double(st.i0)) & (cj0 >= double(st.j0)) & (ci < double(st.i1)) & (cj < double(st.j1));
                    if (!detail::all_lanes(idle | strained)) {
                        for (int l = 0; l < 4; ++l) shift(i + l, j);
                        return;
                    }
                    const v4d c = idle ? zero : cj0 * double(mx) + ci0;  // lanes that keep their increment read cell 0
                    for (int l = 0; l < 4; ++l) at[l] = int(c[l]);
                }
                // The strains (xx, yy, xy, yx) of cells at + d (d = 1, mx, mx + 1 where the
                // lane's bit of m is set, else 0), one record a lane, transposed.
                v4d exx, eyy, exy, eyx;
                auto cells = [&](int m, int d, v4d& xx, v4d& yy, v4d& xy, v4d& yx) LPFDM_INLINE {
                    v4d r0, r1, r2, r3;
                    detail::load(&cs[at[0] + (m & 1) * d].xx, r0); detail::load(&cs[at[1] + ((m >> 1) & 1) * d].xx, r1);
                    detail::load(&cs[at[2] + ((m >> 2) & 1) * d].xx, r2); detail::load(&cs[at[3] + ((m >> 3) & 1) * d].xx, r3);
                    detail::transpose_strains(r0, r1, r2, r3, xx, yy, xy, yx);
                };
                cells(0, 0, exx, eyy, exy, eyx);
                const v4m edge = (hx | hy) & ~idle;
                if (!detail::none_of_lanes(edge)) {  // the mean of two or four cells, as shift takes it
                    v4d xx = 0 + exx, yy = 0 + eyy, xy = 0 + exy, yx = 0 + eyx, bxx, byy, bxy, byx;
                    auto add = [&](const v4m& m, int d) LPFDM_INLINE {
                        if (detail::none_of_lanes(m)) return;
                        cells(detail::lane_bits(m), d, bxx, byy, bxy, byx);
                        xx = m ? xx + bxx : xx; yy = m ? yy + byy : yy; xy = m ? xy + bxy : xy; yx = m ? yx + byx : yx;
                    };
                    add(edge & hx, 1);
                    add(edge & hy, mx);
                    add(edge & hx & hy, mx + 1);
                    const v4d iw = hx & hy ? zero + 0.25 : zero + 0.5;
                    exx = edge ? xx * iw : exx; eyy = edge ? yy * iw : eyy; exy = edge ? xy * iw : exy; eyx = edge ? yx * iw : eyx;
                }
                compensate_lanes(exx, eyy, exy, eyx);
#endif
            }
        });
    };
    by_rows(kShiftRows, nr.j0, nr.j1, nr.size(), [&](int j) { each_row(shift_row, j); });
}

// eq. 13-14: du(t + dt/2) = du(t - dt/2) + dt^2/m (F - D), D = alpha |F| sgn(du) (sgn(du -
// mean) with DAMPING WINDOW). Then fixed directions, then moving walls (their reaction is
// what they exert).
LPFDM_DEF void Simulation::integrate() {
    const Range nodes_now{occupied_.i0, occupied_.empty() ? 0 : occupied_.i1 + 1, occupied_.j0, occupied_.empty() ? 0 : occupied_.j1 + 1};
    const Range nr = nodes_now.unite(live_nodes_);
    if (modes_.advect == Advect::Flip) {  // its own step 5, on the same box as its transfer (flip_nodes)
        live_nodes_ = nodes_now.unite(flip_integrate(nr, nodes_now));
        return;
    }
    if (modes_.dynamic) dynamics_begin();  // the ground's step, the boundary forces (SHAKE, ABSORB)
    const double dt2 = sc_.dt_s * sc_.dt_s, alpha = sc_.damping;
    double ke = 0, maxdu = 0;
    const int mx = mx_;
    double *ux_n = dux_.data(), *uy_n = duy_.data(), *nm = nmass_.data(), *fxn = fx_.data(), *fyn = fy_.data();
    double *ux_old = dux_old_.data(), *uy_old = duy_old_.data();
    double *mxm = mean_ux_.empty() ? nullptr : mean_ux_.data(), *mym = mean_uy_.empty() ? nullptr : mean_uy_.data();  // DAMPING WINDOW
    const double beta = mean_beta_;
    // Node n of the nodes this step's cells touch, or the nodes n .. n + 3 in the lanes of
    // a vector T. Each node of nr keeps the increment eq. 13 begins from, in this same pass
    // and by the same threads (what keep_increments does in the reference cycle). Its
    // pointers by value (by reference, the compiler reloaded them after every store).
    auto advance = [ux_n, uy_n, ux_old, uy_old, nm, fxn, fyn, dt2, alpha, mxm, mym, beta](int n, auto tag) LPFDM_INLINE {
        using T = typename decltype(tag)::type;
        constexpr bool one = std::is_same_v<T, double>;
        T m, fx, fy, ux0, uy0;
        detail::load(ux_n + n, ux0); detail::load(uy_n + n, uy0);
        detail::store(ux_old + n, ux0); detail::store(uy_old + n, uy0);
        detail::load(nm + n, m);
        if constexpr (one)
            if (m == 0) {  // no mass, no motion (and no mean motion: DAMPING WINDOW)
                ux_n[n] = uy_n[n] = 0;
                if (mxm) mxm[n] = mym[n] = 0;
                return;
            }
        detail::load(fxn + n, fx); detail::load(fyn + n, fy);
        T ux, uy, rx{}, ry{};
        if (mxm) {  // DAMPING WINDOW: the means (0 at a node without mass)
            detail::load(mxm + n, rx); detail::load(mym + n, ry);
            follow_mean(ux0, beta, rx); follow_mean(uy0, beta, ry);
            if constexpr (!one) {
                const T zero{};
                const auto moving = m != 0;
                rx = moving ? rx : zero; ry = moving ? ry : zero;
            }
            detail::store(mxm + n, rx); detail::store(mym + n, ry);
        }
        damped_increment(ux0, fx, m, dt2, alpha, ux, rx);  // eq. 13, 14
        damped_increment(uy0, fy, m, dt2, alpha, uy, ry);
        if constexpr (!one) {  // no mass, no motion
            const T zero{};
            const auto moving = m != 0;
            ux = moving ? ux : zero; uy = moving ? uy : zero;
        }
        detail::store(ux_n + n, ux); detail::store(uy_n + n, uy);
    };
    double *row_ke_of = row_ke_.data(), *row_du_of = row_du_.data();
    // The kinetic energy of row j, summed in node order, and its largest increment (nodes
    // with mass only); four nodes' terms at a time in the lanes of a vector.
    auto energy_row = [&](int j, auto wide) LPFDM_INLINE {
        double row_ke = 0, row_du = 0;
        int n = j * (mx + 1) + nr.i0;
        const int nend = j * (mx + 1) + nr.i1;
#if LPFDM_WIDE
        if constexpr (decltype(wide)::value) {
            using detail::v4d;
            v4d big{};
            for (; n + 4 <= nend; n += 4) {
                v4d m, ux, uy, ax, ay;
                detail::load(nm + n, m); detail::load(ux_n + n, ux); detail::load(uy_n + n, uy);
                const auto full = m != 0;
                const v4d e = 0.5 * m * (ux * ux + uy * uy);
                const v4d ef = full ? e : v4d{};  // +0 for a node without mass: the sum is unchanged, and no branch
                for (int l = 0; l < 4; ++l) row_ke += ef[l];
                detail::abs_of(ux, ax); detail::abs_of(uy, ay);
                const v4d a = ax < ay ? ay : ax;  // std::max(ax, ay), lane by lane
                big = full && big < a ? a : big;
            }
            for (int l = 0; l < 4; ++l) row_du = std::max(row_du, big[l]);
        }
#else
        (void)wide;
#endif
        for (; n < nend; ++n) {
            const double m = nm[n], ux = ux_n[n], uy = uy_n[n];
            if (m == 0) continue;
            row_ke += 0.5 * m * (ux * ux + uy * uy);
            row_du = std::max(row_du, std::max(std::fabs(ux), std::fabs(uy)));
        }
        row_ke_of[j] = row_ke;
        row_du_of[j] = row_du;
        energy_row_terms(j, nr.i0, nr.i1, wide);  // the energy account's terms of the row
    };
    // Without SHAKE or ABSORB (whose ground and dashpots change increments between eq. 13
    // and the supports) the fixed directions are imposed in eq. 13's pass, row by row, and
    // each row's energy terms made there, while its nodes are in cache: impose_supports
    // later sets the same zeros again and takes the reactions, and the rows where a wall
    // drove a node are made again after it. The same numbers as eq. 13's pass, the supports
    // and then every row's terms (step_reference), one pass over the nodes fewer.
    const bool smooth = modes_.mapping == Mapping::Smooth;
    const bool fused = !modes_.dynamic && !smooth;  // (MAPPING SMOOTH: follow_material between the supports and the rows' terms)
    const std::int32_t *fixed_at = fixed_nodes_.data(), *fixed_row = fixed_rows_.data();
    const std::uint8_t* fixed = fixed_.data();
    auto hold_row = [&](int j) LPFDM_INLINE {
        for (std::int32_t a = fixed_row[j]; a < fixed_row[j + 1]; ++a) {
            const int n = fixed_at[a];
            if (fixed[n] & kFixX) ux_n[n] = 0;
            if (fixed[n] & kFixY) uy_n[n] = 0;
        }
    };
    auto advance_row = [&](int j, auto wide) LPFDM_INLINE {
        const bool row_inside = j >= nodes_now.j0 && j < nodes_now.j1;  // then nr holds nodes_now's columns
        const int ia = row_inside ? nodes_now.i0 : nr.i1, ib = row_inside ? nodes_now.i1 : nr.i1;
        const int n0 = j * (mx + 1);
        auto idle = [&](int i) {  // no mass, no motion
            const int n = n0 + i;
            ux_old[n] = ux_n[n]; uy_old[n] = uy_n[n];
            nm[n] = 0; fxn[n] = fyn[n] = 0; ux_n[n] = uy_n[n] = 0;
            if (mxm) mxm[n] = mym[n] = 0;  // DAMPING WINDOW
        };
        for (int i = nr.i0; i < ia; ++i) idle(i);
        detail::sweep(n0 + ia, n0 + ib, wide, advance);
        for (int i = ib; i < nr.i1; ++i) idle(i);
        if (fused) {
            hold_row(j);
            energy_row(j, wide);
        }
    };
    by_rows(kAdvanceRows, nr.j0, nr.j1, nr.size(), [&](int j) { each_row(advance_row, j); });
    integrated_ = nr;
    if (modes_.dynamic) absorb_increments();  // the dashpots of ABSORB
    const Range wall_nodes = impose_supports();
    if (smooth) follow_material(nr);  // MAPPING SMOOTH: the nodes beyond the material (its section)
    const int e0 = fused ? std::max(nr.j0, wall_nodes.j0) : nr.j0, e1 = fused ? std::min(nr.j1, wall_nodes.j1) : nr.j1;
    if (e0 < e1) by_rows(kEnergyRows, e0, e1, long(e1 - e0) * (nr.i1 - nr.i0), [&](int j) { each_row(energy_row, j); });
    for (int j = nr.j0; j < nr.j1; ++j) {
        ke += row_ke_[std::size_t(j)];
        maxdu = std::max(maxdu, row_du_[std::size_t(j)]);
    }
    ke_ = ke / dt2;
    max_du_ = maxdu;
    if (!nr.empty()) tally_energy(nr.j0, nr.j1);
    live_nodes_ = nodes_now.unite(wall_nodes);
}

// ======================================================================================
// RESTART: THE STATE A SIMULATION SAVES
// ======================================================================================

LPFDM_DEF void Simulation::resumed() {
    for (auto* v : {&fx_, &fy_, &nmass_prev_, &cvol_, &svxx_, &svyy_, &svxy_, &hgx_, &hgy_}) std::fill(v->begin(), v->end(), 0.0);
    std::fill(strain_.begin(), strain_.end(), CellStrain{});
    std::fill(carried_.begin(), carried_.end(), Carried{});
    Landing t;
    for (std::size_t k = 0; k < p_.size(); ++k) {
        const int c = p_.cell[k];
        t.cmin = std::min(t.cmin, c); t.cmax = std::max(t.cmax, c);
        const int i = p_.x[k] >= 0 ? std::min(mx_ - 1, int(p_.x[k] * invL_)) : c % mx_;
        t.imin = std::min(t.imin, i); t.imax = std::max(t.imax, i);
    }
    occupied_ = landed(t);
    // MAPPING SMOOTH: the sums made anew (the centroids the next step reads,
    // cell_centroid), and the box of every cell the points' squares touch.
    if (modes_.mapping == Mapping::Smooth && overlap_.size() < p_.size()) overlap_.resize(p_.size());  // (the step's scratch, as at set-up)
    if (modes_.advect == Advect::Flip && flip_gx_.size() < p_.size()) { flip_gx_.resize(p_.size()); flip_gy_.resize(p_.size()); }
    if (modes_.mapping == Mapping::Smooth) map_points();
    strained_ = occupied_.grow(2, mx_, my_);
    live_nodes_ = integrated_ = {0, mx_ + 1, 0, my_ + 1};
    parts_known_ = false;
    chunk_team_ = 0;
    p_.each_array([&](const char*, auto& v, Points::Use, bool state) { if (!state && !v.empty()) v.resize(p_.size()); });
    driven_nodes_.clear();
    for (std::size_t n = 0; n < driven_.size(); ++n)
        if (driven_[n]) driven_nodes_.push_back(std::int32_t(n));
    mark_wall_cells();  // the cells the walls' faces may be crossed from, at the travel read
    if (modes_.dynamic) replay_ground();  // the ground's motion to this step, and the edges released at START
}

template <class S, class F> inline void Simulation::visit_state(S& s, F& f) {
    f("step", s.step_); f("parked", s.parked_); f("mass_in", s.mass_in_); f("mass_out", s.mass_out_); f("mass_initial", s.mass0_);
    f("ke", s.ke_); f("max_du", s.max_du_); f("rx", s.rx_); f("ry", s.ry_);
    f("du_x", s.dux_); f("du_y", s.duy_); f("node_mass", s.nmass_); f("cell_mass", s.cmass_);
    for (std::size_t w = 0; w < s.walls_.size(); ++w) {
        f("wall_shift_i", s.walls_[w].shift_i); f("wall_shift_j", s.walls_[w].shift_j);
        f("wall_fx", s.walls_[w].fx); f("wall_fy", s.walls_[w].fy); f("wall_dx", s.walls_[w].dx); f("wall_dy", s.walls_[w].dy);
        f("wall_vx", s.sc_.walls[w].vx); f("wall_vy", s.sc_.walls[w].vy);
        f("wall_dx0", s.walls_[w].dx0); f("wall_dy0", s.walls_[w].dy0);  // the faces' last travel (hold_by_walls)
    }
    if (s.modes_.advect == Advect::Flip && !s.walls_.empty()) f("node_driven", s.driven_);  // the nodes the walls drove last (flip_transfer)
    // The energy account's running sums (energy()).
    auto& e = s.es_;
    f("energy_w_walls", e.w_walls); f("energy_w_fixes", e.w_fixes); f("energy_w_gravity", e.w_gravity); f("energy_d_damping", e.d_damping);
    f("energy_h_walls", e.h_walls); f("energy_h_fixes", e.h_fixes); f("energy_h_gravity", e.h_gravity); f("energy_h_damping", e.h_damping);
    f("energy_kinetic", e.kinetic); f("energy_peak_kinetic", e.peak_kinetic);
    f("energy_left_strain", e.left_strain); f("energy_left_potential", e.left_potential); f("energy_left_plastic", e.left_plastic);
    f("energy_strain0", e.strain0); f("energy_potential0", e.potential0);
    if (s.modes_.dynamic) {  // SHAKE, ABSORB (the ground's own motion is replayed: resumed())
        f("energy_w_ground", e.w_ground); f("energy_h_ground", e.h_ground); f("energy_h_input", e.h_input);
        f("energy_d_absorb", e.d_absorb); f("energy_h_absorb", e.h_absorb); f("energy_w_held", e.w_held); f("energy_h_held", e.h_held);
        f("absorb_hold_x", s.hold_fx_); f("absorb_hold_y", s.hold_fy_);
    }
    if (s.modes_.advect == Advect::Flip) f("energy_d_slip", e.d_slip);                    // ADVECT FLIP (flip_slip)
    if (s.sc_.shift) { f("energy_w_shift", e.w_shift); f("shift_moved", s.shifted_); }      // SHIFT (shift_points)
    if (s.modes_.water) { f("water_drained", s.drained_); f("water_d_water", s.d_water_); }  // WATER
    if (s.modes_.loads) { f("load_work", s.w_loads_); f("load_work_half", s.h_loads_); }     // LOAD
    if (!s.mean_ux_.empty()) { f("damping_mean_x", s.mean_ux_); f("damping_mean_y", s.mean_uy_); }  // DAMPING WINDOW
}

// ======================================================================================
// FACTOR OF SAFETY BY STRENGTH REDUCTION (lpfdm --fos; not in the paper)
//
// By what factor F could the soil's strength fall before the scene fails? Each trial
// runs the scene from its start with every Mohr-Coulomb material's strength divided by
// F, and F is bracketed between the largest trial that stands and the smallest that
// fails: FLAC's strength-reduction solve (Dawson, Roth and Drescher 1999), and what
// finite-element codes do with the loss of convergence (Griffiths and Lane 1999).
// Where this is open, the choices (each tested in tests/test_fos.cpp):
// * The reduction (strength_reduced): c / F, tan(phi) / F, tan(psi) / F (a dilation
//   below friction stays below it) and TENSION / F. The apex c / tan(phi) does not move,
//   so a tension limit below it stays below it. SOFTEN (a fraction of c) stays; SCATTER
//   scatters each point about the reduced means with the same coefficient and seed (each
//   point's c is exactly its c / F). Elastic materials and user models stay as they are.
// * Stands (fos_trial): the unbalanced-force ratio (Simulation::unbalanced_ratio) below
//   kAtRest at two readings in a row (kFosRead steps apart: one reading can fall on an
//   oscillation's turning of force) within FosOptions::responses N_r steps. N_r, the scene's
//   response time (response_steps), is the number of steps it takes to come to rest so
//   with unlimited strength (every Mohr-Coulomb material elastic), at most its STEPS: a
//   scene that does not come to rest even so has no factor (NeverAtRest). Rest alone
//   cannot tell failure here, since a slope that fails flows and comes to rest at the end
//   of its runout; within the budget, a failing slope is still moving. Near the factor
//   the motion slows (a trial 1 % above it moves for long), which the budget measures in
//   the scene's own time, as FLAC's N_r does.
// * The bracket (factor_of_safety): from F = 1, doubling or halving until one trial
//   stands and one fails, within FosOptions::smallest and largest; then halving the
//   bracket until it is at most FosOptions::tol wide. F is its middle.
// ======================================================================================

namespace detail {
constexpr long kFosRead = 10;  // steps between readings of the unbalanced-force ratio

// Runs sim up to budget steps, reading the ratio every kFosRead steps: the steps run when
// it fell below kAtRest at two readings in a row (-1 if it did not), the last ratio read,
// and whether the run stayed healthy.
inline long steps_to_rest(Simulation& sim, long budget, double& ratio, bool& healthy) {
    int below = 0;
    healthy = true;
    for (long n = 1; n <= budget; ++n) {
        sim.step();
        if (!sim.healthy()) { healthy = false; return -1; }
        if (n % kFosRead && n != budget) continue;
        ratio = sim.unbalanced_ratio();
        below = ratio < kAtRest ? below + 1 : 0;
        if (below == 2) return n;
    }
    return -1;
}
}  // namespace detail

LPFDM_DEF Scene strength_reduced(const Scene& s, double F) {
    Scene r = s;
    const double rad = detail::kPi / 180;
    for (Material& m : r.materials) {
        if (m.model != Model::MohrCoulomb) continue;
        m.c /= F;
        m.phi_deg = std::atan(std::tan(m.phi_deg * rad) / F) / rad;
        m.psi_deg = std::atan(std::tan(m.psi_deg * rad) / F) / rad;
        if (m.tension >= 0) m.tension /= F;
    }
    return r;
}

LPFDM_DEF long response_steps(const Scene& s, Kernel k, double* ratio) {
    Scene e = s;
    for (Material& m : e.materials)
        if (m.model == Model::MohrCoulomb) m.model = Model::Elastic;
    Simulation sim(e, k);
    double r = 0;
    bool healthy = true;
    const long n = detail::steps_to_rest(sim, s.steps, r, healthy);
    if (ratio) *ratio = r;
    return n;
}

LPFDM_DEF FosTrial fos_trial(const Scene& s, double F, long budget, Kernel k) {
    FosTrial t;
    t.F = F;
    Simulation sim(strength_reduced(s, F), k);
    bool healthy = true;
    const long n = detail::steps_to_rest(sim, budget, t.ratio, healthy);
    t.stands = n > 0;
    t.trouble = !healthy;
    t.steps = sim.step_count();
    const Points& p = sim.points();
    for (std::size_t q = 0; q < p.size(); ++q) {
        const std::size_t id = std::size_t(p.id[q]);
        t.moved = std::max(t.moved, std::hypot(p.x[q] - sim.initial_x()[id], p.y[q] - sim.initial_y()[id]));
    }
    return t;
}

LPFDM_DEF FosResult factor_of_safety(const Scene& s, const FosOptions& o, const std::function<void(const FosTrial&)>& told) {
    FosResult r;
    r.response_steps = response_steps(s, o.kernel, &r.ratio);
    if (r.response_steps < 0) {
        r.outcome = FosResult::NeverAtRest;
        r.response_steps = s.steps;
        return r;
    }
    r.budget = o.responses * r.response_steps;
    auto stands = [&](double F) {
        r.trials.push_back(fos_trial(s, F, r.budget, o.kernel));
        if (told) told(r.trials.back());
        return r.trials.back().stands;
    };
    double lo = 0, hi = 0;  // the largest factor that stood, the smallest that failed (0: none yet)
    for (double F = 1; lo == 0 || hi == 0;) {
        if (F > o.largest) { r.outcome = FosResult::StandsAtLargest; r.stands_at = r.F = lo; return r; }
        if (F < o.smallest) { r.outcome = FosResult::FailsAtSmallest; r.fails_at = r.F = hi; return r; }
        if (stands(F)) { lo = F; F *= 2; }
        else { hi = F; F /= 2; }
    }
    while (hi - lo > o.tol) {
        const double F = 0.5 * (lo + hi);
        (stands(F) ? lo : hi) = F;
    }
    r.stands_at = lo;
    r.fails_at = hi;
    r.F = 0.5 * (lo + hi);
    return r;
}

// A face drawn across the lattice (a CLUSTER POLYGON's edge neither level nor upright) and
// filled by cells is a staircase of cells. Where the soil is too weak for a riser of one
// cell to stand (a vertical cut stands to 4 c tan(45 + phi/2) / (rho g), Rankine's, below
// L), --fos reads such a face far below its slope's factor (the steps' corners keep moving
// at every cell size, and points carried over the risers come to lie alone in cells above
// the face: the nodes above them, which nothing stiff holds, keep the unbalanced force
// up): a 2:1 face of dry
// cohesionless soil with phi = psi = 35 degrees reads 0.74, 0.88 and 1.18 with the paper's
// mapping, MAPPING SMOOTH and ADVECT FLIP, against 1.40 (tests/README.md, "Factor of
// safety"). Warned at the edge's first vertex, once a cluster, where the edge is a free
// face: at some point along it the cell a cell's width inside is the cluster's own and the
// cell as far outside holds no cluster (a buried interface is not warned of). Not warned
// of: a cluster drawn with FILL=POINTS and PPC=2 under MAPPING SMOOTH without ADVECT FLIP,
// whose cells along the face are partly full (decks/verify_drawn_slope.deck: 1.48, 1.46,
// 1.44 at 10, 20, 40 cells over H). Warned of otherwise: under the paper's mapping it still
// reads 0.74 (its points along the face come to lie alone above it as before); PPC=1 makes
// FILL=CELLS's points; PPC=4 reads high (1.59, 1.53, 1.48); FLIP was not measured.
LPFDM_DEF Diagnostics fos_warnings(const Scene& s) {
    Diagnostics d;
    const double L = s.cell_m, g = std::hypot(s.gravity_x, s.gravity_y);
    if (!detail::warn_map_fits(s) || !(g > 0)) return d;
    const int mx = s.mx, my = s.my;
    const std::vector<int> owner = detail::cluster_owners(s.clusters, L, mx, my);
    auto owner_at = [&](double x, double y) {  // -1: no cluster; -2: outside the lattice
        const double i = std::floor(x / L), j = std::floor(y / L);
        if (!(i >= 0 && j >= 0 && i < mx && j < my)) return -2;
        return owner[std::size_t(j) * std::size_t(mx) + std::size_t(i)];
    };
    for (std::size_t ci = 0; ci < s.clusters.size(); ++ci) {
        const Cluster& k = s.clusters[ci];
        const Material* m = s.material(k.mat);
        if (!m || m->model != Model::MohrCoulomb || k.polygon.size() < 6) continue;
        // verified: FILL=POINTS with 2 x 2 points a cell under MAPPING SMOOTH, no FLIP (tests/README.md, "Factor of safety")
        const bool smooth_points = k.fill_points && s.mapping == Mapping::Smooth;
        if (smooth_points && k.ppc == 2 && s.advect != Advect::Flip) continue;
        const double cut = 4 * m->c * std::tan((45 + 0.5 * m->phi_deg) * detail::kPi / 180) / (m->rho * g);
        if (!(cut < L)) continue;
        const std::size_t n = k.polygon.size() / 2;
        double area = 0;  // twice the signed area: > 0 anticlockwise
        for (std::size_t v = 0; v < n; ++v) {
            const std::size_t w = (v + 1) % n;
            area += k.polygon[2 * v] * k.polygon[2 * w + 1] - k.polygon[2 * w] * k.polygon[2 * v + 1];
        }
        for (std::size_t v = 0; v < n; ++v) {
            const std::size_t w = (v + 1) % n;
            const double ax = k.polygon[2 * v], ay = k.polygon[2 * v + 1], bx = k.polygon[2 * w], by = k.polygon[2 * w + 1];
            if (ax == bx || ay == by) continue;
            const double len = std::hypot(bx - ax, by - ay), ox = (area > 0 ? 1 : -1) * (by - ay) / len, oy = (area > 0 ? -1 : 1) * (bx - ax) / len;
            bool free = false;  // (the outward normal (ox, oy); samples every half cell along the edge)
            for (double t = 0.5 * L; t < len && !free; t += 0.5 * L) {
                const double x = ax + (bx - ax) * t / len, y = ay + (by - ay) * t / len;
                free = owner_at(x - ox * L, y - oy * L) == int(ci) && owner_at(x + ox * L, y + oy * L) == -1;
            }
            if (!free) continue;
            d.push_back({k.polygon_pos.size() > 2 * v ? k.polygon_pos[2 * v] : k.pos,
                         "--fos does not verify a free face across the lattice in soil too weak for a riser of one cell to stand: this edge, (" + shortest(ax) +
                             ", " + shortest(ay) + ") to (" + shortest(bx) + ", " + shortest(by) + ") m, of MATERIAL " + std::to_string(k.mat) +
                             " (a vertical cut stands to 4 c tan(45 + phi/2) / (rho g) = " + shortest(cut) + " m, L = " + shortest(L) +
                             (smooth_points ? " m); with FILL=POINTS under MAPPING SMOOTH it is verified with PPC=2 and no ADVECT FLIP only (PPC=4 reads 6-14 % high at 40-10 cells over H)"
                                            : " m); such a face reads far below its slope's factor unless drawn with FILL=POINTS and PPC=2 under MAPPING SMOOTH") +
                             " (decks/README.md, \"Factor of safety\")",
                         true});
            break;
        }
    }
    return d;
}

// ======================================================================================
// CHECKS
//
// Where the paper is open, the choices made here (each tested in tests/):
// * Stability: dt must not exceed L sqrt(rho / ((M + lambda)(1 + alpha))), M = K + 4G/3,
//   lambda = K - 2G/3: below L / c_p, the limit of a full lattice, because a lone cell
//   has a faster mode and local damping stiffens the fastest one (see stable_dt).
// ======================================================================================

// Whether v lies in key k's range (a whole number where it must be one). unset: the
// fallback of an optional parameter is accepted too (TENSION -1: the apex), as in a scene
// built in code; a deck that writes it out of range is refused.
inline bool in_range(const DeckKey& k, double v, bool unset = false) {
    if (unset && v == k.fallback && k.param && !k.required) return true;
    if (!(k.lo_open ? v > k.lo : v >= k.lo) || !(k.hi_open ? v < k.hi : v <= k.hi)) return false;
    return !k.whole || v == std::floor(v);
}
// Whether key k may hold v in scene object `index` of s: in_range, and PSI at most PHI.
inline bool key_ok(const DeckKey& k, double v, const Scene& s, std::size_t index, bool unset = false) {
    if (std::strcmp(k.name, "PSI") == 0 && std::strcmp(k.card, "MATERIAL") == 0 && !(v <= s.materials[index].phi_deg)) return false;
    return in_range(k, v, unset);
}
// x in the fewest digits that read back as x (0.1 as "0.1", 6 as "6", 20 as "20", not
// "2e+01"): a number of the deck as it was written, in a message. Exponents only outside
// [1e-4, 1e15).
LPFDM_DEF std::string shortest(double x) {
    char b[48];
    const bool plain = x == 0 || (std::fabs(x) >= 1e-4 && std::fabs(x) < 1e15);
    for (int p = plain ? 0 : 1; p <= 17; ++p) {
        std::snprintf(b, sizeof b, plain ? "%.*f" : "%.*g", p, x);
        if (std::strtod(b, nullptr) == x) break;
    }
    return b;
}
// The message for a value v outside key k's range: "<subject> must lie in [lo, hi)".
inline std::string range_message(const DeckKey& k, double v) {
    auto num = [](double x) {
        char b[32];
        if (x == std::floor(x) && std::fabs(x) < 1e15) std::snprintf(b, sizeof b, "%.0f", x);
        else std::snprintf(b, sizeof b, "%g", x);
        return std::string(b);
    };
    const std::string subj = k.subject;
    if (std::strcmp(k.card, "MATERIAL") == 0 && std::strcmp(k.name, "PSI") == 0) return "PSI must lie in [0, PHI]";
    if (std::strcmp(k.card, "MATERIAL") == 0 && std::strcmp(k.name, "SCATTER") == 0 && v > k.hi)
        return "SCATTER above 0.5 makes the truncation at c >= 0 and phi > 0 dominate the distribution";
    if (std::strcmp(k.card, "MATERIAL") == 0 && std::strcmp(k.name, "SCATTER") == 0) return "SCATTER must be >= 0";
    if (k.whole) return subj + " must be a whole number in [" + num(k.lo) + ", " + num(k.hi) + "]";
    if (k.hi == kHuge) return subj + " must be " + (k.lo_open ? "> " : ">= ") + num(k.lo) + k.unit;
    return subj + " must lie in " + (k.lo_open ? "(" : "[") + num(k.lo) + ", " + num(k.hi) + (k.hi_open ? ")" : "]") + k.unit;
}
// The key of a card by name (upper case), or nullptr.
inline const DeckKey* deck_key(const std::string& card, const std::string& name) {
    for (const DeckKey& k : kDeckKeys)
        if (card == k.card && name == k.name) return &k;
    return nullptr;
}
// The parameters of a card (for MATERIAL, of a model: kElastic or kMohr), as "E, NU, RHO".
// The keys of a card (for MATERIAL, of a model): its parameters, or (settable) those --set
// may change.
inline std::vector<std::string> key_names(const std::string& card, int model, bool settable) {
    std::vector<std::string> v;
    for (const DeckKey& k : kDeckKeys)
        if (card == k.card && (settable ? k.settable : k.param) && (!model || (k.models & model))) v.push_back(k.name);
    return v;
}
inline std::string joined(const std::vector<std::string>& names) {
    std::string list;
    for (const std::string& n : names) list += (list.empty() ? "" : ", ") + n;
    return list;
}
// The one of candidates close to what was written (case aside): one edit away (two for
// words of more than four letters; a swap of neighbours is one edit), or what was written
// begins it; else "".
LPFDM_DEF std::string nearest_name(const std::string& written, const std::vector<std::string>& candidates) {
    std::string w;
    for (char ch : written) w += char(std::toupper(static_cast<unsigned char>(ch)));
    auto distance = [](const std::string& a, const std::string& b) {  // optimal string alignment
        std::vector<std::vector<int>> d(a.size() + 1, std::vector<int>(b.size() + 1));
        for (std::size_t i = 0; i <= a.size(); ++i) d[i][0] = int(i);
        for (std::size_t j = 0; j <= b.size(); ++j) d[0][j] = int(j);
        for (std::size_t i = 1; i <= a.size(); ++i)
            for (std::size_t j = 1; j <= b.size(); ++j) {
                d[i][j] = std::min({d[i - 1][j] + 1, d[i][j - 1] + 1, d[i - 1][j - 1] + (a[i - 1] != b[j - 1])});
                if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1]) d[i][j] = std::min(d[i][j], d[i - 2][j - 2] + 1);
            }
        return d[a.size()][b.size()];
    };
    std::string best;
    int best_d = w.size() > 4 ? 3 : 2;
    for (const std::string& c : candidates) {
        std::string u;
        for (char ch : c) u += char(std::toupper(static_cast<unsigned char>(ch)));
        const int dd = w.size() >= 3 && u.compare(0, w.size(), w) == 0 ? 1 : distance(w, u);
        if (dd < best_d) { best_d = dd; best = c; }
    }
    return best;
}
// " (did you mean X?)" with X the nearest_name, or "".
LPFDM_DEF std::string did_you_mean(const std::string& written, const std::vector<std::string>& candidates) {
    const std::string best = nearest_name(written, candidates);
    return best.empty() ? "" : " (did you mean " + best + "?)";
}
// The names of every card.
LPFDM_DEF std::vector<std::string> card_names() {
    std::vector<std::string> v;
    for (const DeckCard& c : kDeckCards) v.push_back(c.name);
    return v;
}

// A card's synopsis from the table: "CLUSTER mat x0 y0 x1 y1 [PPC=2]" (deck_help adds a
// CLUSTER's FILL=, whose value is a word).
LPFDM_DEF std::string card_synopsis(const DeckCard& c) {
    std::string out = c.name;
    auto word = [&](const std::string& w) { if (!w.empty()) out += " " + w; };
    word(c.before);
    for (const DeckKey& k : kDeckKeys)
        if (!k.param && std::strcmp(k.card, c.name) == 0) {
            std::string n = k.name;
            if (n != "L") for (char& ch : n) ch = char(std::tolower(static_cast<unsigned char>(ch)));
            word(n);
        }
    word(c.after);
    for (const DeckKey& k : kDeckKeys) {
        if (!k.param || std::strcmp(k.card, c.name) != 0) continue;
        char fb[32];
        std::snprintf(fb, sizeof fb, "%g", k.fallback);
        const bool unset = !in_range(k, k.fallback);  // the fallback means "not given" (TENSION: the apex)
        word(k.required ? std::string(k.name) + "=.." : "[" + std::string(k.name) + "=" + (unset ? std::string(k.whole ? "n" : "..") : fb) + "]");
    }
    return out;
}

// --help's list of the cards and the --set keys, from the tables above.
LPFDM_DEF std::string deck_help() {
    std::string out = "deck cards (decks/README.md explains each):\n";
    for (const DeckCard& c : kDeckCards) {
        const bool cluster = std::strcmp(c.name, "CLUSTER") == 0;
        std::string line = "  " + card_synopsis(c) + (cluster ? " [FILL=CELLS]" : "");  // (a word's value: read by read_cluster)
        line.resize(std::max<std::size_t>(line.size() + 1, 58), ' ');
        out += line + c.meaning + "\n";
        if (cluster) {  // its second form and FILL=POINTS, read by the deck reader
            line = "  CLUSTER mat POLYGON x1 y1 x2 y2 ... [PPC=2] [FILL=CELLS]";
            line.resize(std::max<std::size_t>(line.size() + 1, 58), ' ');
            out += line + "the same in the polygon (a centre on an edge counts; & continues the card)\n";
            line = "  ... FILL=POINTS";
            line.resize(std::max<std::size_t>(line.size() + 1, 58), ' ');
            out += line + "only the points whose own places lie in the box or polygon: a face across the lattice is not a staircase of cells\n";
        }
    }
    out += "--set keys (CARD.KEY; MATERIAL and WALL by id, CLUSTER, FIX, SHAKE and OUTPUT by order from 1):\n";
    for (const DeckCard& c : kDeckCards) {
        const std::vector<std::string> keys = key_names(c.name, 0, true);
        if (!keys.empty()) out += std::string("  ") + c.name + ": " + joined(keys) + "\n";
    }
    return out;
}

// Stable time step of the lattice. A full lattice is stable up to L / c_p, but a lone
// cell (any free corner of a body) has a faster mode, stiffness M + lambda instead of
// M (M = K + 4G/3, lambda = K - 2G/3; 2G when lambda < 0), and local damping makes the
// fastest mode see (1 + alpha) times its stiffness:
//     dt <= L sqrt(rho / ((M + lambda)(1 + alpha)))   for the stiffest material,
// K of a saturated material (WATER) with the water's Kw / n added (undrained, the stiffest).
// Measured (tests/test_hard.cpp): the limit at alpha = 0.8 is 0.74-0.75 of L / c_p,
// predicted 0.745; a lone cell at nu = 0.25 0.866, predicted sqrt(3/4).
LPFDM_DEF double stable_dt(const Scene& s) {
    double dt = std::numeric_limits<double>::infinity(), alpha = largest_damping(s);
    for (const auto& m : s.materials) {
        const double K = m.bulk() + (s.water.on && m.porosity > 0 ? s.water.kw / m.porosity : 0.0);  // WATER: Kw / n
        const double G = m.shear(), M = K + 4 * G / 3, lam = K - 2 * G / 3;
        const double k = (lam >= 0 ? M + lam : 2 * G) * (1 + alpha);
        dt = std::min(dt, s.cell_m * std::sqrt(m.rho / k));
    }
    return dt;
}

// Overrides one parameter of a scene, as a parameter study does: key is CARD.PARAM with
// the card's id (MATERIAL, WALL) or its 1-based position among cards of its kind
// (CLUSTER, FIX) glued to it, e.g. MATERIAL1.C, CLUSTER2.PPC, WALL1.VY, DAMPING.ALPHA,
// STEP.DT, STEP.N, GRAVITY.GY, SEED.N, GRID.L. Returns an empty string or the problem.
LPFDM_DEF std::string apply_setting(Scene& s, const std::string& key_in, double v) {
    std::string key;
    for (char ch : key_in) key += char(std::toupper(static_cast<unsigned char>(ch)));
    const std::size_t dot = key.find('.');
    if (dot == std::string::npos) return "expected CARD.PARAM=VALUE, e.g. MATERIAL1.C=12000";
    std::string card = key.substr(0, dot);
    const std::string par = key.substr(dot + 1);
    std::size_t d = card.size();
    while (d > 0 && std::isdigit(static_cast<unsigned char>(card[d - 1]))) --d;
    const int num = d < card.size() ? std::atoi(card.c_str() + d) : 0;
    card.resize(d);
    bool known = false;
    for (const DeckKey& k : kDeckKeys) known |= card == k.card;
    if (!known) return "unknown setting " + key_in + " (e.g. MATERIAL1.C, CLUSTER1.PPC, WALL1.VY, DAMPING.ALPHA, STEP.DT, STEP.N, GRAVITY.GY, SEED.N, GRID.L)" + did_you_mean(card, card_names());
    // Which card of its kind: MATERIAL and WALL by id, the others by their order from 1.
    std::size_t index = 0, count = 0;
    int model = 0;
    if (card == "MATERIAL" || card == "WALL") {
        bool found = false;
        const std::size_t n = card == "MATERIAL" ? s.materials.size() : s.walls.size();
        for (std::size_t i = 0; i < n && !found; ++i)
            if ((card == "MATERIAL" ? s.materials[i].id : s.walls[i].id) == num) { index = i; found = true; }
        if (!found) return "no " + card + " with id " + std::to_string(num);
        if (card == "MATERIAL") model = s.materials[index].model == Model::MohrCoulomb ? kMohr : kElastic;
    } else if (card == "CLUSTER" || card == "FIX" || card == "OUTPUT" || card == "SHAKE" || card == "TRACK" || card == "DRAIN" || card == "LOAD") {
        count = card == "CLUSTER" ? s.clusters.size() : card == "FIX" ? s.fixes.size() : card == "SHAKE" ? s.shakes.size()
                : card == "TRACK" ? s.tracks.size() : card == "DRAIN" ? s.drains.size() : card == "LOAD" ? s.loads.size() : s.outputs.size();
        if (num < 1 || std::size_t(num) > count) return "there is no " + card + " number " + std::to_string(num) + " (cards of a kind count from 1)";
        index = std::size_t(num - 1);
    }
    if ((card == "WATER" && !s.water.on) || (card == "RESERVOIR" && !s.reservoir.on) || (card == "GEOSTATIC" && !s.geostatic) || (card == "SHIFT" && !s.shift))
        return "the deck has no " + card + " card: " + key_in + " would change nothing";
    const DeckKey* k = deck_key(card, par);
    if (card == "CLUSTER" && par == "FILL")
        return "CLUSTER " + std::to_string(num) + "'s FILL is a word (CELLS or POINTS), and --set takes numbers: write it on the card (--set takes " +
               (s.clusters[index].polygon.empty() ? "MAT, X0, Y0, X1, Y1, PPC" : "MAT, PPC") + ")";
    if (!k || !k->settable) {
        const std::vector<std::string> names = key_names(card, model, true);
        return card + " has no parameter " + par + " (it takes " + joined(names) + ")" + did_you_mean(par, names);
    }
    if (card == "CLUSTER" && !s.clusters[index].polygon.empty() && (par == "X0" || par == "Y0" || par == "X1" || par == "Y1"))
        return "CLUSTER " + std::to_string(num) + " is a POLYGON: " + par + " is a box's corner, and --set cannot move a polygon's vertices (it takes MAT, PPC)";
    if (model && !(k->models & model))
        return card + " " + std::to_string(num) + " is " + (model == kMohr ? "MOHR" : "ELASTIC") + ": " + par + " is not one of its parameters (" + joined(key_names("MATERIAL", model, false)) + ")";
    if (!in_range(*k, v, true)) return range_message(*k, v);  // before storing: it may not fit the member
    const double was = k->get(s, index);
    k->set(s, index, v);
    if (!key_ok(*k, v, s, index, true)) { k->set(s, index, was); return range_message(*k, v); }
    return "";
}
namespace detail {
// Where cluster c of scene s (a well-formed box or polygon on a lattice) falls short: a box
// with its corners swapped, a part past the lattice's edges (each edge named, the numbers
// as the deck writes them), or no cell centre inside (the nearest named). The message, or
// "" when it fills cells; `where` its place in the deck (a polygon's coordinate past an
// edge, else the card).
inline std::string cluster_place_problem(const Scene& s, const Cluster& c, Pos& where) {
    const double X = s.mx * s.cell_m, Y = s.my * s.cell_m, tol = 1e-3 * s.cell_m;
    const bool poly = !c.polygon.empty();
    auto coord_pos = [&](std::size_t k) { return k < c.polygon_pos.size() ? c.polygon_pos[k] : c.pos; };
    if (!poly && (c.box.x0 > c.box.x1 || c.box.y0 > c.box.y1)) { where = c.pos; return "the box needs x0 <= x1 and y0 <= y1"; }
    // Each edge crossed, the numbers as the deck writes them (the shortest form that
    // reads back the same), the lattice's to ten digits.
    auto ten = [](double x) {
        char b[32];
        std::snprintf(b, sizeof b, "%.10g", x);
        return std::string(b);
    };
    std::string past;
    std::size_t first_out = std::string::npos;
    auto edge = [&](bool out, const std::string& field, double v, const char* name, const char* axis, double at) {
        if (out) past += (past.empty() ? "" : "; ") + field + " = " + shortest(v) + " m is past its " + name + " edge " + axis + " = " + ten(at) + " m";
    };
    std::vector<double> corners;  // the polygon, or the box's corners
    if (poly) {
        corners = c.polygon;
        for (std::size_t k = 0; k + 1 < corners.size(); k += 2) {
            const double x = corners[k], y = corners[k + 1];
            const std::string vertex = "vertex " + std::to_string(k / 2 + 1) + " ";
            if ((x < -tol || x > X + tol) && first_out == std::string::npos) first_out = k;
            if ((y < -tol || y > Y + tol) && first_out == std::string::npos) first_out = k + 1;
            edge(x < -tol, vertex + "x", x, "left", "x", 0.0);
            edge(x > X + tol, vertex + "x", x, "right", "x", X);
            edge(y < -tol, vertex + "y", y, "bottom", "y", 0.0);
            edge(y > Y + tol, vertex + "y", y, "top", "y", Y);
        }
    } else {
        corners = {c.box.x0, c.box.y0, c.box.x1, c.box.y0, c.box.x1, c.box.y1, c.box.x0, c.box.y1};
        edge(c.box.x0 < -tol, "x0", c.box.x0, "left", "x", 0.0);
        edge(c.box.x1 > X + tol, "x1", c.box.x1, "right", "x", X);
        edge(c.box.y0 < -tol, "y0", c.box.y0, "bottom", "y", 0.0);
        edge(c.box.y1 > Y + tol, "y1", c.box.y1, "top", "y", Y);
    }
    const char* what = poly ? "polygon" : "box";
    if (!past.empty()) {
        where = poly ? coord_pos(first_out) : c.pos;
        return std::string("the cluster ") + what + " reaches outside the lattice: " + past + " (the lattice is [0, " + ten(X) + "] x [0, " + ten(Y) + "] m)";
    }
    // FILL=POINTS: the points' places, the centres of the lattice of spacing L / PPC
    int n = c.fill_points ? std::clamp(c.ppc, 1, 32) : 1;
    if (double(s.mx) * n > 2e9 || double(s.my) * n > 2e9) n = 1;  // (a lattice past GRID's bounds: refused elsewhere)
    bool any = false;
    detail::cluster_cells(c, s.cell_m / n, s.mx * n, s.my * n, [&](int, int, int) { any = true; });
    if (!any) {
        double cx = 0, cy = 0, dist = 0;
        detail::nearest_centre(corners, s.cell_m / n, s.mx * n, s.my * n, cx, cy, dist);
        char b[64];
        std::snprintf(b, sizeof b, "%.3g", dist);
        where = c.pos;
        return std::string("the cluster ") + what + (c.fill_points ? " holds no point's place (FILL=POINTS, PPC=" + std::to_string(c.ppc) + ")" : std::string(" holds no cell centre")) +
               ": the nearest is (" + shortest(cx) + ", " + shortest(cy) + ") m, " + b + " m from it";
    }
    return "";
}
}  // namespace detail

// Everything that would make a scene unrunnable, with the card each problem came from.
// All problems are reported, not the first; what `unread` names is not checked again.
namespace detail {
// The directions wall w sets at its start: a rough one both, a SMOOTH one across its line
// (a column of nodes x, a row y; Simulation::impose_supports).
inline int wall_dirs(const Scene& s, const Wall& w) {
    if (!w.smooth) return kFixX | kFixY;
    int i0, i1, j0, j1;
    wall_span(w.box, s.cell_m, s.mx, s.my, i0, i1, j0, j1);
    return i1 == i0 ? int(kFixX) : int(kFixY);
}
// Constraints combine: a wall may share nodes with a FIX or an earlier wall where they set
// different directions (a SMOOTH wall's x beside a smooth base's FIX Y). Where both set one
// direction at a node of both boxes, wall a is refused: the message names both cards and
// the nodes; "" when it is not.
inline std::string wall_conflict(const Scene& s, std::size_t a) {
    const Wall& w = s.walls[a];
    const int wd = wall_dirs(s, w);
    auto clash = [&](const Box& o, int od, const std::string& other) -> std::string {
        int i0, i1, j0, j1;
        box_nodes({std::max(w.box.x0, o.x0), std::max(w.box.y0, o.y0), std::min(w.box.x1, o.x1), std::min(w.box.y1, o.y1)}, s.cell_m, s.mx, s.my, i0, i1, j0, j1);
        if (!(wd & od) || i1 < i0 || j1 < j0) return "";
        const char* d = (wd & od) == (kFixX | kFixY) ? "x and y" : (wd & od) == kFixX ? "x" : "y";
        auto span = [&](int a0, int a1) { return shortest(a0 * s.cell_m) + (a1 > a0 ? " to " + shortest(a1 * s.cell_m) : std::string()); };
        return "WALL " + std::to_string(w.id) + " and " + other + " both set " + d + " at the nodes they share (x = " + span(i0, i1) +
               " m, y = " + span(j0, j1) + " m)";
    };
    for (const Fix& f : s.fixes)
        if (std::string m = clash(f.box, f.dirs, "the FIX at line " + std::to_string(f.pos.line)); !m.empty()) return m;
    for (std::size_t b = 0; b < a; ++b)
        if (std::string m = clash(s.walls[b].box, wall_dirs(s, s.walls[b]), "WALL " + std::to_string(s.walls[b].id) + " (line " +
                                  std::to_string(s.walls[b].pos.line) + ")"); !m.empty())
            return m;
    return "";
}
}  // namespace detail

namespace detail {
// validate's checks of the cards of the section "Pore water and loads" (WATER, DRAIN, LOAD,
// RESERVOIR, GEOSTATIC) and of the flow's stable step.
inline void water_checks(const Scene& s, const Unread& unread, Diagnostics& d) {
    auto err = [&](const Pos& p, std::string m) { d.push_back({p, std::move(m)}); };
    const bool lattice = s.mx > 0 && s.my > 0 && s.cell_m > 0;
    auto keys = [&](const char* card, std::size_t index, const Pos& pos) {
        for (const DeckKey& k : kDeckKeys)
            if (std::strcmp(k.card, card) == 0 && !key_ok(k, k.get(s, index), s, index, true)) err(pos, range_message(k, k.get(s, index)));
    };
    auto node_count = [&](const Box& b) {
        if (b.x0 > b.x1 || b.y0 > b.y1) return -1L;
        int i0, i1, j0, j1;
        box_nodes(b, s.cell_m, s.mx, s.my, i0, i1, j0, j1);
        return (i1 < i0 || j1 < j0) ? 0L : (i1 - i0 + 1L) * (j1 - j0 + 1L);
    };
    // WATER, DRAIN, LOAD (the section "Pore water and loads")
    if (s.water.on) {
        keys("WATER", 0, s.water.pos);
        bool saturated = false;
        for (const Material& m : s.materials) saturated |= m.porosity > 0;
        if (!saturated && !unread.materials) err(s.water.pos, "WATER, but no MATERIAL has POROSITY: no material holds water");
    }
    for (const Material& m : s.materials) {
        if (m.porosity > 0 && !s.water.on) err(m.pos, "POROSITY makes the material saturated: the deck needs a WATER card");
        if (m.perm > 0 && !(m.porosity > 0)) err(m.pos, "PERM without POROSITY: a dry material has no water to conduct");
    }
    if (s.geostatic) {
        keys("GEOSTATIC", 0, s.geostatic_pos);
        if (s.gravity_y >= 0 || s.gravity_x != 0) err(s.geostatic_pos, "GEOSTATIC needs gravity straight down (GRAVITY 0 gy, gy < 0)");
    }
    if (s.reservoir.on) {
        keys("RESERVOIR", 0, s.reservoir.pos);
        if (!s.water.on) err(s.reservoir.pos, "RESERVOIR needs a WATER card (its density; the pore water it drains)");
        if (s.gravity_y >= 0 || s.gravity_x != 0) err(s.reservoir.pos, "RESERVOIR needs gravity straight down (GRAVITY 0 gy, gy < 0): its pressure is rho_w |gy| (level - y)");
    }
    for (std::size_t a = 0; a < s.drains.size(); ++a) {
        const Drain& dr = s.drains[a];
        keys("DRAIN", a, dr.pos);
        if (!s.water.on) err(dr.pos, "DRAIN needs a WATER card");
        else if (s.water.undrained) err(dr.pos, "DRAIN with WATER UNDRAINED: no water flows");
        if (!lattice) continue;
        const long n = node_count(dr.box);
        if (n < 0) err(dr.pos, "the box needs x0 <= x1 and y0 <= y1");
        else if (n < 2) err(dr.pos, "the DRAIN box holds " + std::string(n == 0 ? "no node" : "one node") + ": it drains the cell edges whose two nodes it holds");
    }
    for (std::size_t a = 0; a < s.loads.size(); ++a) {
        const Load& ld = s.loads[a];
        keys("LOAD", a, ld.pos);
        if (ld.box.x0 != ld.box.x1 && ld.box.y0 != ld.box.y1) err(ld.pos, "a LOAD is a line: give x0 = x1 (a column of nodes) or y0 = y1 (a row)");
        else if (lattice) {
            const long n = node_count(ld.box);
            if (n < 0) err(ld.pos, "the line needs x0 <= x1 and y0 <= y1");
            else if (n < 2) err(ld.pos, "the LOAD line holds " + std::string(n == 0 ? "no node" : "one node") + ": a traction needs a line of two nodes or more");
        }
    }
    if (s.water.on && !s.water.undrained && lattice && !unread.step && s.dt_s > 0 && std::isfinite(s.water.kw)) {
        const double g = std::hypot(s.gravity_x, s.gravity_y), gw = s.water.rhow * (g > 0 ? g : 9.81);
        double lim = std::numeric_limits<double>::infinity();
        for (const Material& m : s.materials)
            if (m.porosity > 0 && m.perm > 0) lim = std::min(lim, m.porosity * s.cell_m * s.cell_m * gw / ((s.drains.empty() && !s.reservoir.on ? 8 : 12) * s.water.kw * m.perm));
        if (s.dt_s > lim) {
            char buf[200];
            std::snprintf(buf, sizeof buf, "time step %.6g s is above the pore water's stable limit %.6g s (n L^2 gamma_w / (%d KW PERM) of the most permeable material)", s.dt_s, lim, s.drains.empty() && !s.reservoir.on ? 8 : 12);
            err(s.step_pos, buf);
        }
    }
}
}  // namespace detail

namespace detail {
// validate's time step: at most the stable limit (stable_dt), and DAMPING WINDOW=t at least
// two steps: each step takes dt / t of the way to the new increment, and over less the mean
// all but follows the increment and the damping's sign, taken about it, is rounding (a
// window of dt pushed psc.deck until a node jumped). Without any damping the window has
// nothing to act on and is not asked about.
inline void time_step_checks(const Scene& s, const Unread& unread, Diagnostics& d) {
    auto err = [&](const Pos& p, std::string m) { d.push_back({p, std::move(m)}); };
    if (unread.step || !(s.dt_s > 0)) return;
    if (!s.materials.empty()) {
        const double lim = stable_dt(s);
        if (s.dt_s > lim) {
            char buf[160];
            std::snprintf(buf, sizeof buf, "time step %.6g s is above the stable limit %.6g s (L sqrt(rho / ((M + lambda)(1 + damping))) of the stiffest material)", s.dt_s, lim);
            err(s.step_pos, buf);
        }
    }
    if (largest_damping(s) > 0 && s.damping_window > 0 && s.dt_s > 0.5 * s.damping_window)
        err(s.damping_pos.line > 0 || s.shakes.empty() ? s.damping_pos : s.shakes.front().pos,
            "DAMPING WINDOW=" + shortest(s.damping_window) + " s is shorter than two time steps, 2 dt = " + shortest(2 * s.dt_s) + " s");
}
}  // namespace detail

LPFDM_DEF Diagnostics validate(const Scene& s, const Unread& unread) {
    Diagnostics d;
    auto err = [&](const Pos& p, std::string m) { d.push_back({p, std::move(m)}); };
    const bool lattice = s.mx > 0 && s.my > 0 && s.cell_m > 0;  // else nothing can be placed
    if (!lattice && !unread.grid) err(s.grid_pos, "the lattice needs mx > 0, my > 0 cells and a cell size L > 0");
    const double X = s.mx * s.cell_m, Y = s.my * s.cell_m, tol = 1e-3 * s.cell_m;
    // Every number of kDeckKeys in its range (for a material, the keys of its model).
    // SCATTER at most 0.5: beyond it more than 2.3 % of draws fall below zero and the
    // truncated sample's mean drifts by more than 3 %: truncation, not the Gaussian, decides.
    auto keys = [&](const char* card, std::size_t index, const Pos& pos, int model) {
        for (const DeckKey& k : kDeckKeys) {
            if (std::strcmp(k.card, card) != 0 || (model && k.models && !(k.models & model))) continue;
            const double v = k.get(s, index);
            if (!key_ok(k, v, s, index, true)) err(pos, range_message(k, v));
        }
    };
    keys("GRAVITY", 0, s.grid_pos, 0);
    keys("DAMPING", 0, s.damping_pos, 0);
    keys("HOURGLASS", 0, s.grid_pos, 0);
    keys("REORDER", 0, s.grid_pos, 0);
    if (s.shift) keys("SHIFT", 0, s.shift_pos, 0);
    if (!unread.step) keys("STEP", 0, s.step_pos, 0);
    for (std::size_t a = 0; a < s.outputs.size(); ++a) keys("OUTPUT", a, s.outputs[a].pos, 0);
    for (std::size_t a = 0; a < s.materials.size(); ++a) {
        const Material& m = s.materials[a];
        for (std::size_t b = 0; b < a; ++b)
            if (s.materials[b].id == m.id) err(m.pos, "material " + std::to_string(m.id) + " is defined twice");
        keys("MATERIAL", a, m.pos, m.model == Model::MohrCoulomb ? kMohr : kElastic);
        if (m.model != Model::MohrCoulomb) continue;
        if (m.phi_deg == 0 && m.c == 0) err(m.pos, "PHI = 0 and C = 0: the material has no strength");
        if (m.scatter > 0 && m.phi_deg > 0 && (90 - m.phi_deg) < 2 * m.scatter * m.phi_deg)
            err(m.pos, "SCATTER too large for this PHI: more than 2.3 % of draws would pass 90 degrees");
    }
    if (s.clusters.empty() && !unread.clusters) err(s.grid_pos, "the scene has no CLUSTER: nothing to compute");
    for (std::size_t a = 0; a < s.clusters.size(); ++a) {
        const Cluster& c = s.clusters[a];
        const Material* m = s.material(c.mat);
        if (!m && !unread.materials) err(c.pos, "material " + std::to_string(c.mat) + " is not defined");
        keys("CLUSTER", a, c.pos, 0);
        const bool poly = !c.polygon.empty();
        auto coord_pos = [&](std::size_t k) { return k < c.polygon_pos.size() ? c.polygon_pos[k] : c.pos; };
        if (poly) {
            std::size_t at = 0;
            const std::string problem = detail::polygon_problem(c.polygon, at);
            if (!problem.empty()) { err(coord_pos(at), problem); continue; }
        }
        if (!lattice) continue;
        Pos where = c.pos;
        if (const std::string p = detail::cluster_place_problem(s, c, where); !p.empty()) err(where, p);
    }
    auto node_count = [&](const Box& b) {
        if (b.x0 > b.x1 || b.y0 > b.y1) return -1L;
        int i0, i1, j0, j1;
        detail::box_nodes(b, s.cell_m, s.mx, s.my, i0, i1, j0, j1);
        return (i1 < i0 || j1 < j0) ? 0L : (i1 - i0 + 1L) * (j1 - j0 + 1L);
    };
    for (std::size_t a = 0; a < s.fixes.size(); ++a) {
        const Fix& f = s.fixes[a];
        keys("FIX", a, f.pos, 0);
        if (f.dirs < 1 || f.dirs > 3) err(f.pos, "unknown direction");
        if (!lattice) continue;
        const long n = node_count(f.box);
        if (n < 0) err(f.pos, "the box needs x0 <= x1 and y0 <= y1");
        else if (n == 0) err(f.pos, "the FIX box holds no node");
    }
    for (std::size_t a = 0; a < s.walls.size(); ++a) {
        const Wall& w = s.walls[a];
        keys("WALL", a, w.pos, 0);
        for (std::size_t b = 0; b < a; ++b)
            if (s.walls[b].id == w.id) err(w.pos, "wall " + std::to_string(w.id) + " is defined twice");
        if (!lattice) continue;
        const long n = node_count(w.box);
        if (n < 0) err(w.pos, "the box needs x0 <= x1 and y0 <= y1");
        else if (n == 0) err(w.pos, "the WALL box holds no node");
        if (w.smooth && n > 0) {
            int i0, i1, j0, j1;
            detail::wall_span(w.box, s.cell_m, s.mx, s.my, i0, i1, j0, j1);
            if ((i1 > i0) == (j1 > j0)) err(w.pos, "a SMOOTH wall is one line of nodes, a row or a column (it is driven across that line)");
        }
        if (!unread.step && std::isfinite(w.vx) && std::isfinite(w.vy) && s.dt_s > 0 && std::hypot(w.vx, w.vy) * s.dt_s > 0.1 * s.cell_m) {
            char buf[120];
            std::snprintf(buf, sizeof buf, "the wall moves %.3g cells per step; at most 0.1 is allowed (lower the speed or the time step)",
                          std::hypot(w.vx, w.vy) * s.dt_s / s.cell_m);
            err(w.pos, buf);
        }
        if (n > 0)
            if (const std::string c = detail::wall_conflict(s, a); !c.empty()) err(w.pos, c);
    }
    detail::water_checks(s, unread, d);  // WATER, DRAIN, LOAD, RESERVOIR, GEOSTATIC
    for (std::size_t a = 0; a < s.shakes.size(); ++a) {
        const Shake& k = s.shakes[a];
        keys("SHAKE", a, k.pos, 0);
        const std::string problem = record_problem(k);
        if (!problem.empty()) err(k.pos, "the motion record " + problem);
        if (!unread.step && s.dt_s > 0 && std::isfinite(k.start) && k.start / s.dt_s > 1e15) err(k.pos, "START is more than 1e15 time steps away");
        // BASELINE integrates the record step by step when the run is set up: bounded.
        if (problem.empty() && k.baseline && !unread.step && s.dt_s > 0 && k.t.back() / s.dt_s > 1e8)
        {
            char buf[200];
            std::snprintf(buf, sizeof buf, "the motion record lasts %g s, %.3g steps of dt: BASELINE integrates at most 1e8 (shorten the record's quiet end, or take a larger dt)",
                          k.t.back(), k.t.back() / s.dt_s);
            err(k.pos, buf);
        }
        if (k.dir != kFixX && k.dir != kFixY) err(k.pos, "a SHAKE card shakes X or Y");
        for (std::size_t b = 0; b < a; ++b) {
            const Shake& o = s.shakes[b];
            if (o.dir == k.dir) err(k.pos, std::string("the ground is shaken in ") + (k.dir == kFixX ? "X" : "Y") + " twice (SHAKE at line " + std::to_string(o.pos.line) + ")");
            else if (o.start != k.start || o.damping != k.damping || o.compliant != k.compliant)
                err(k.pos, "the SHAKE cards must agree on START, DAMPING and COMPLIANT (line " + std::to_string(o.pos.line) + " differs)");
        }
    }
    for (const Shake& k : s.shakes) {
        bool held = false;
        for (const Fix& f : s.fixes) held |= (f.dirs & k.dir) != 0;
        if (!k.compliant && !held && !unread.fixes)
            err(k.pos, std::string("SHAKE ") + (k.dir == kFixX ? "X" : "Y") + " moves the nodes fixed in " + (k.dir == kFixX ? "X" : "Y") +
                           ", and no FIX card holds that direction (or make it COMPLIANT: through an absorbing base)");
    }
    if (s.absorb & ~(kBottom | kTop | kLeft | kRight)) err(s.absorb_pos, "ABSORB names BOTTOM, TOP, LEFT or RIGHT");
    if (s.outflow & ~(kBottom | kTop | kLeft | kRight)) err(s.outflow_pos, "OUTFLOW names BOTTOM, TOP, LEFT or RIGHT");
    if (lattice && s.absorb)  // a wall drives its nodes: a dashpot there would only be overruled, its energy counted twice
        for (const Wall& w : s.walls) {
            const bool on = ((s.absorb & kLeft) && w.box.x0 <= tol) || ((s.absorb & kRight) && w.box.x1 >= X - tol) ||
                            ((s.absorb & kBottom) && w.box.y0 <= tol) || ((s.absorb & kTop) && w.box.y1 >= Y - tol);
            if (on) err(w.pos, "the wall starts on an edge of the lattice that ABSORB makes absorbing (line " + std::to_string(s.absorb_pos.line) + "): a wall drives its nodes");
        }
    if (s.advect == Advect::Points && s.mapping == Mapping::Smooth)
        err(s.advect_pos, "ADVECT POINTS carries increments cell by cell: it works with MAPPING PAPER only");
    if (s.advect == Advect::Points && s.motion == Motion::Paper && !unread.motion)
        err(s.advect_pos, "ADVECT POINTS needs MOTION CENTRE or BILINEAR: carried from eq. 7a/7b about node [1], the increments grow without bound");
    if (s.advect == Advect::Flip) {  // see Simulation::flip_transfer
        if (s.mapping != Mapping::Smooth && !unread.mapping) err(s.advect_pos, "ADVECT FLIP needs MAPPING SMOOTH: the points' increments go to the lattice, and its change back, by their squares' weights");
        if (s.motion != Motion::Bilinear && s.motion != Motion::Default)
            err(s.advect_pos, "ADVECT FLIP needs MOTION BILINEAR (the default with MAPPING SMOOTH): the points move by the field their increments are interpolated from");
    }
    if (lattice) detail::time_step_checks(s, unread, d);  // the stable limit, DAMPING WINDOW
    return d;
}

namespace detail {
// Material over an opening: under gravity, a line of cells (a column for GRAVITY's gy,
// a row for its gx) whose material has no held line of nodes beneath it, down to the
// lattice's edge, falls out through that edge (held: fixed or walled in the direction of
// gravity; an ABSORB edge counts as held). OUTFLOW names the edges it is meant to leave by.
inline void opening_warnings(const Scene& s, Diagnostics& d) {
    if (!warn_map_fits(s)) return;
    const int mx = s.mx, my = s.my;
    const std::vector<int> owner = cluster_owners(s.clusters, s.cell_m, mx, my);
    std::vector<std::uint8_t> held(std::size_t(mx + 1) * std::size_t(my + 1), 0);
    auto hold = [&](int i0, int i1, int j0, int j1, int dirs) {
        for (int j = std::max(j0, 0); j <= std::min(j1, my); ++j)
            for (int i = std::max(i0, 0); i <= std::min(i1, mx); ++i) held[std::size_t(j) * std::size_t(mx + 1) + std::size_t(i)] |= std::uint8_t(dirs);
    };
    int i0, i1, j0, j1;
    for (const Fix& f : s.fixes) {
        box_nodes(f.box, s.cell_m, mx, my, i0, i1, j0, j1);
        hold(i0, i1, j0, j1, f.dirs);
    }
    for (const Wall& w : s.walls) {
        wall_span(w.box, s.cell_m, mx, my, i0, i1, j0, j1);
        hold(i0, i1, j0, j1, wall_dirs(s, w));  // a SMOOTH wall holds across its line only
    }
    struct Edge { int bit; const char* name; bool down; };  // down: gravity points out through it
    const Edge edges[] = {{kBottom, "BOTTOM", s.gravity_y < 0}, {kTop, "TOP", s.gravity_y > 0}, {kLeft, "LEFT", s.gravity_x < 0}, {kRight, "RIGHT", s.gravity_x > 0}};
    for (const Edge& e : edges) {
        if (!e.down || (s.outflow & e.bit) || (s.absorb & e.bit)) continue;
        const bool across_y = e.bit == kBottom || e.bit == kTop;  // columns of cells fall through it
        const int lines = across_y ? mx : my, depth = across_y ? my : mx;
        // cell a of line at d cells from the edge; the nodes of its side towards the edge
        auto cell_at = [&](int a, int d, int& i, int& j) {
            i = across_y ? a : (e.bit == kLeft ? d : mx - 1 - d);
            j = across_y ? (e.bit == kBottom ? d : my - 1 - d) : a;
        };
        auto side_held = [&](int a, int d) {
            int i, j;
            cell_at(a, d, i, j);
            const int dir = across_y ? kFixY : kFixX;
            int n0, n1;  // the two nodes
            if (e.bit == kBottom) { n0 = j * (mx + 1) + i; n1 = n0 + 1; }
            else if (e.bit == kTop) { n0 = (j + 1) * (mx + 1) + i; n1 = n0 + 1; }
            else if (e.bit == kLeft) { n0 = j * (mx + 1) + i; n1 = n0 + (mx + 1); }
            else { n0 = j * (mx + 1) + i + 1; n1 = n0 + (mx + 1); }
            return (held[std::size_t(n0)] & dir) && (held[std::size_t(n1)] & dir);
        };
        int first = -1, last = -1, count = 0, cluster = -1;
        for (int a = 0; a < lines; ++a) {
            int d0 = 0, i = 0, j = 0;
            for (; d0 < depth; ++d0) {
                cell_at(a, d0, i, j);
                if (owner[std::size_t(j) * std::size_t(mx) + std::size_t(i)] >= 0) break;
            }
            if (d0 == depth) continue;  // no material along this line
            bool open = true;
            for (int d = d0; d >= 0 && open; --d) open = !side_held(a, d);
            if (!open) continue;
            if (first < 0) { first = a; cluster = owner[std::size_t(j) * std::size_t(mx) + std::size_t(i)]; }
            if (last < 0 || a == last + 1 || count == 0) last = a;
            ++count;
        }
        if (count == 0) continue;
        const char* what = across_y ? (count == 1 ? "column" : "columns") : (count == 1 ? "row" : "rows");
        const char* axis = across_y ? "x" : "y";
        char b[320];
        std::snprintf(b, sizeof b,
                      "material over an opening falls out through the lattice's %s edge under gravity: %d %s of cells (the first %d to %d, %s = %s to %s m) "
                      "have no fixed or walled line of nodes beneath their material; OUTFLOW %s says it is meant",
                      e.name, count, what, first, last, axis, shortest(first * s.cell_m).c_str(), shortest((last + 1) * s.cell_m).c_str(), e.name);
        Diagnostic w;
        w.pos = s.clusters[std::size_t(cluster)].pos; w.message = b; w.warning = true;
        d.push_back(std::move(w));
    }
}
}  // namespace detail

// What is legal but probably a mistake, as warnings (the program's --strict makes them
// errors). Units are SI and angles degrees, so a number off by a unit's factor runs
// without complaint; these rules catch the usual slips:
//   PHI or PSI in (0, 1.6)       radians? (pi/2 = 1.571; no soil has a friction or
//                                dilation angle below 1.6 degrees worth giving)
//   PHI or PSI above 60 degrees  beyond any soil; radians times 100, or a typing slip?
//   E below 1 kPa                kPa or MPa? (the softest soils are about 1 MPa)
//   RHO below 100 kg/m^3         t/m^3 or g/cm^3? (dry soils weigh 1200-2200 kg/m^3)
//   NU at or above 0.495         nearly incompressible: K > 100 G, a short time step, and
//                                eq. 5's one strain per cell locks in plastic flow
//   dt above 0.95 of the limit   the limit (stable_dt) is an estimate; the shipped decks
//                                run at up to 0.94 of it, measured stable
//   OUTPUT EVERY above the steps the run writes its last frame or row only
//   SHAKE moving the ground more than L/4   the lattice does not follow it (a record
//                                that drifts: BASELINE)
//   material over an opening     it falls out of the lattice (opening_warnings; OUTFLOW)
// Each warning is at the card it comes from. What `unread` names is not looked at.
LPFDM_DEF Diagnostics warnings(const Scene& s, const Unread& unread) {
    Diagnostics d;
    char b[256];
    auto warn = [&](const Pos& p) {
        Diagnostic w;
        w.pos = p; w.message = b; w.warning = true;
        d.push_back(std::move(w));
    };
    for (const Material& m : s.materials) {
        if (m.model == Model::MohrCoulomb) {
            const std::pair<const char*, double> angles[] = {{"PHI", m.phi_deg}, {"PSI", m.psi_deg}};
            for (const auto& a : angles) {
                if (a.second > 0 && a.second < 1.6) {
                    std::snprintf(b, sizeof b, "%s = %g degrees: is it in radians (%.3g degrees)? angles are in degrees", a.first, a.second,
                                  a.second * 180 / 3.14159265358979323846);
                    warn(m.pos);
                } else if (a.second > 60 && a.second < 90) {
                    std::snprintf(b, sizeof b, "%s = %g degrees is above 60: more than any soil has", a.first, a.second);
                    warn(m.pos);
                }
            }
        }
        if (m.E > 0 && m.E < 1e3) {
            std::snprintf(b, sizeof b, "E = %g Pa is below 1 kPa: is it in kPa or MPa? the deck's unit is Pa", m.E);
            warn(m.pos);
        }
        if (m.rho > 0 && m.rho < 100) {
            std::snprintf(b, sizeof b, "RHO = %g kg/m^3 is below 100: is it in t/m^3 or g/cm^3? the deck's unit is kg/m^3", m.rho);
            warn(m.pos);
        }
        if (m.nu >= 0.495 && m.nu < 0.5) {
            std::snprintf(b, sizeof b, "NU = %g is nearly incompressible (K = %.3g G): the stable time step is short and the cells lock in plastic flow",
                          m.nu, 2 * (1 + m.nu) / (3 * (1 - 2 * m.nu)));
            warn(m.pos);
        }
    }
    if (!unread.step && !unread.grid && s.cell_m > 0 && s.dt_s > 0 && !s.materials.empty()) {
        const double lim = stable_dt(s);
        if (s.dt_s > 0.95 * lim && s.dt_s <= lim) {
            std::snprintf(b, sizeof b, "time step %.6g s is %.3f of the stable limit %.6g s: so near it, a run may become unstable", s.dt_s,
                          s.dt_s / lim, lim);
            warn(s.step_pos);
        }
    }
    if (!unread.grid && s.cell_m > 0 && largest_damping(s) > 0 && s.damping_window > 0 && !s.materials.empty()) {
        // DAMPING WINDOW: a mean over less than the slowest elastic period follows that
        // vibration, and eq. 14 about it no longer damps it (decks/column.deck with 0.03 s,
        // a tenth of its period: still moving after 6000 steps)
        double cp = std::numeric_limits<double>::infinity();
        for (const auto& m : s.materials) cp = std::min(cp, m.p_wave_speed());
        const double period = 4 * std::max(s.mx, s.my) * s.cell_m / cp;
        if (s.damping_window < period) {
            std::snprintf(b, sizeof b, "DAMPING WINDOW=%g s is shorter than 4 W / c_p = %.3g s, the slowest elastic period the lattice holds (W its longer side, c_p the slowest material's): the scene may not come to rest",
                          s.damping_window, period);
            warn(s.damping_pos);
        }
    }
    if (!unread.step && !unread.grid && s.cell_m > 0 && s.dt_s > 0 && s.steps >= 1)
        for (const Shake& k : s.shakes) {
            if (k.compliant || !record_problem(k).empty() || !std::isfinite(k.scale)) continue;
            const double most = detail::ground_excursion(k, s.dt_s, s.steps);
            if (most > 0.25 * s.cell_m) {
                std::snprintf(b, sizeof b, "the ground moves up to %.3g m in this run, %.2g cells: the lattice stays put, so points may leave at its edges%s", most,
                              most / s.cell_m, k.baseline ? "" : " (BASELINE takes off the record's drift)");
                warn(k.pos);
            }
        }
    if (!unread.grid && !unread.clusters && !unread.fixes) detail::opening_warnings(s, d);
    // ADVECT FLIP with one point a cell: a centred point's square is its cell, its weights a
    // quarter at each corner, so a checkerboard of the points' increments sums to nothing
    // at every node; the lattice and its damping never see it, and as the points move it
    // feeds the lattice (tests/test_energy.cpp: column.deck never comes to rest)
    if (s.advect == Advect::Flip && !unread.clusters)
        for (const Cluster& c : s.clusters)
            if (c.ppc == 1) {
                std::snprintf(b, sizeof b, "ADVECT FLIP with PPC=1: a checkerboard of the points' increments is invisible to the lattice and to damping, and rings on "
                                           "(column.deck: unbalanced ratio 0.01 after 6000 steps, 3e-6 with PPC=2; the footing's q/c 22-33 %% high): use PPC=2 or more");
                warn(c.pos);
            }
    // (measured: decks/README's RESERVOIR paragraph; the header's "Pore water and loads")
    if (s.reservoir.on && s.water.on && s.mapping == Mapping::Smooth && s.advect != Advect::Flip && !unread.mapping) {
        std::snprintf(b, sizeof b, "with MAPPING SMOOTH and no ADVECT FLIP the reservoir's pressure misses the parts of squares past the material's faces: "
                                   "drawdown.deck draws 0.11 m^3/m of water in as it stands (FLIP: 0.0006) and its crest settles 1.26 m (0.64); add ADVECT FLIP");
        warn(s.reservoir.pos);
    }
    if (!unread.step && s.steps >= 1)
        for (const Output& o : s.outputs)
            if (o.every > s.steps) {
                std::snprintf(b, sizeof b, "EVERY %ld is more than the %ld steps of the run: %s", o.every, s.steps,
                              o.kind == Output::History ? "only the last row is written" : "only the first and last frames are written");
                warn(o.pos);
            }
    return d;
}
// Diagnostics in the order of the deck: by file, line and column (stable: the messages
// of one place keep the order they were found in).
// (std::sort on the indices, the first index breaking ties: std::stable_sort takes its
// buffer from the nothrow operator new, which a program counting allocations may not
// replace along with the plain one.)
LPFDM_DEF void sort_diagnostics(std::vector<Diagnostic>& d) {
    std::vector<std::size_t> order(d.size());
    for (std::size_t k = 0; k < order.size(); ++k) order[k] = k;
    std::sort(order.begin(), order.end(), [&](std::size_t i, std::size_t j) {
        const Pos &a = d[i].pos, &b = d[j].pos;
        if (a.file != b.file) return a.file < b.file;
        if (a.line != b.line) return a.line < b.line;
        if (a.col != b.col) return a.col < b.col;
        return i < j;
    });
    std::vector<Diagnostic> sorted;
    sorted.reserve(d.size());
    for (std::size_t k : order) sorted.push_back(std::move(d[k]));
    d = std::move(sorted);
}
// One diagnostic at file:line:col, as a list (built member by member: g++ 12 at -O3 warns
// that a braced {{file, line, col}, message} may be used uninitialized).
LPFDM_DEF Diagnostics one_error(const std::string& file, int line, int col, std::string message) {
    Diagnostic d;
    d.pos.file = file; d.pos.line = line; d.pos.col = col;
    d.message = std::move(message);
    Diagnostics v;
    v.push_back(std::move(d));
    return v;
}

// ======================================================================================
// DECK READER, WRITERS, STATE FILES
// ======================================================================================

#ifndef LPFDM_NO_IO
// ---------------------------------------------------------- deck reader ---

namespace detail {

struct Token {
    std::string text;
    Pos pos;
};

// Fortran real: [sign] digits [. digits] [E|D [sign] digits], or . digits; no nan/inf.
// *out_of_range is set when the form is right but the value does not fit a double.
inline bool parse_real(const std::string& t, double& out, bool* out_of_range = nullptr) {
    if (out_of_range) *out_of_range = false;
    std::string s;
    std::size_t i = 0;
    if (i < t.size() && (t[i] == '+' || t[i] == '-')) s += t[i++];
    std::size_t digits = 0;
    while (i < t.size() && std::isdigit(static_cast<unsigned char>(t[i]))) { s += t[i++]; ++digits; }
    if (i < t.size() && t[i] == '.') {
        s += t[i++];
        while (i < t.size() && std::isdigit(static_cast<unsigned char>(t[i]))) { s += t[i++]; ++digits; }
    }
    if (digits == 0) return false;
    if (i < t.size() && (t[i] == 'e' || t[i] == 'E' || t[i] == 'd' || t[i] == 'D')) {
        s += 'e'; ++i;
        if (i < t.size() && (t[i] == '+' || t[i] == '-')) s += t[i++];
        std::size_t ed = 0;
        while (i < t.size() && std::isdigit(static_cast<unsigned char>(t[i]))) { s += t[i++]; ++ed; }
        if (ed == 0) return false;
    }
    if (i != t.size()) return false;
    if (s[0] == '+') s.erase(0, 1);
    const char* b = s.data();
    const auto r = std::from_chars(b, b + s.size(), out);
    if (r.ec == std::errc::result_out_of_range) {
        if (out_of_range) *out_of_range = true;
        return false;
    }
    return r.ec == std::errc() && r.ptr == b + s.size() && std::isfinite(out);
}

inline std::string upper(std::string s) {
    for (auto& ch : s) ch = char(std::toupper(static_cast<unsigned char>(ch)));
    return s;
}
// s without the characters of `chars` at either end (TITLE's text).
inline std::string trimmed(const std::string& s, const char* chars) {
    const std::size_t b = s.find_first_not_of(chars);
    return b == std::string::npos ? std::string() : s.substr(b, s.find_last_not_of(chars) - b + 1);
}

// Splits the deck into cards: comments removed, continuations joined, each field
// with its own line and column. Fields are separated by blanks or commas; '=' stands
// alone so that NAME=VALUE, NAME = VALUE and NAME= VALUE read alike.
struct Lexed {
    std::vector<std::vector<Token>> cards;
    std::vector<std::string> raw;  // the card's text after the keyword (for TITLE)
};

// The next line of text from `at` on (without its LF) into line; false at the end.
inline bool next_line(const std::string& text, std::size_t& at, std::string& line) {
    if (at >= text.size()) return false;
    std::size_t eol = text.find('\n', at);
    if (eol == std::string::npos) eol = text.size();
    line.assign(text, at, eol - at);
    at = eol + 1;
    return true;
}

// The text without a leading UTF-8 byte order mark, its CR LF and lone CR (old Mac files)
// made LF. In one pass (erasing each CR in place took quadratic time on a large file).
inline std::string unix_lines(const std::string& in) {
    std::string out;
    out.reserve(in.size());
    for (std::size_t i = in.compare(0, 3, "\xEF\xBB\xBF") == 0 ? 3 : 0; i < in.size(); ++i) {
        if (in[i] != '\r') out += in[i];
        else if (i + 1 >= in.size() || in[i + 1] != '\n') out += '\n';  // a lone CR; of CR LF the LF follows
    }
    return out;
}

inline Lexed lex(const std::string& text_in, const std::string& file, Diagnostics& diags) {
    const std::string text = unix_lines(text_in);
    Lexed out;
    std::vector<Token> pending;
    std::string pending_raw;
    bool continuing = false;
    Pos last_amp;
    int line_no = 0;
    std::size_t at = 0;
    std::string line;
    while (detail::next_line(text, at, line)) {
        ++line_no;
        bool binary = false;
        for (std::size_t c = 0; c < line.size(); ++c) {
            const unsigned char ch = static_cast<unsigned char>(line[c]);
            if ((ch < 0x20 && ch != '\t' && ch != '\f' && ch != '\v') || ch == 0x7f) {
                char buf[96];
                std::snprintf(buf, sizeof buf, "the deck holds binary data (byte 0x%02x); a deck is plain text", ch);
                diags.push_back({{file, line_no, int(c) + 1}, buf});
                binary = true;
                break;
            }
        }
        if (binary) return {};  // one message is enough for a binary file
        if (!line.empty() && line[0] == '*') continue;  // comment card
        const std::size_t bang = line.find('!');
        if (bang != std::string::npos) line.resize(bang);
        // Columns as GNU tools count them: a tab advances to the next multiple of 8.
        std::vector<int> col(line.size() + 1, 1);
        for (std::size_t c = 0; c < line.size(); ++c) col[c + 1] = line[c] == '\t' ? (col[c] - 1) / 8 * 8 + 9 : col[c] + 1;
        std::vector<Token> toks;
        std::size_t c = 0;
        while (c < line.size()) {
            const char ch = line[c];
            if (ch == ' ' || ch == '\t' || ch == ',' || ch == '\f' || ch == '\v') { ++c; continue; }
            if (ch == '=') { toks.push_back({"=", {file, line_no, col[c]}}); ++c; continue; }
            const std::size_t b = c;
            while (c < line.size() && !std::strchr(" \t,=\f\v", line[c])) ++c;
            toks.push_back({line.substr(b, c - b), {file, line_no, col[b]}});
        }
        const bool amp = !toks.empty() && toks.back().text == "&";
        if (amp) {
            last_amp = toks.back().pos;
            toks.pop_back();
            line.resize(line.rfind('&'));
        }
        if (toks.empty() && !amp) continue;  // blank or comment only: also inside a continuation
        if (!continuing) {
            pending.clear();
            pending_raw.clear();
            if (!toks.empty()) {
                const std::size_t kw_end = toks[0].pos.col - 1 + toks[0].text.size();
                pending_raw = kw_end < line.size() ? line.substr(kw_end) : "";
            }
        } else {
            pending_raw += " " + line;
        }
        {  // one blank between the pieces of a continued TITLE
            std::string& t = pending_raw;
            std::string out;
            for (char ch : t) if (!(ch == ' ' || ch == '\t') || out.empty() || out.back() != ' ') out += (ch == '\t' ? ' ' : ch);
            t = out;
        }
        pending.insert(pending.end(), toks.begin(), toks.end());
        continuing = amp;
        if (!continuing && !pending.empty()) {
            out.cards.push_back(pending);
            out.raw.push_back(pending_raw);
            if (upper(pending[0].text) == "END") return out;  // whatever follows END is not read
        }
    }
    if (continuing) diags.push_back({last_amp, "'&' continues the card, but no line follows"});
    return out;
}

// Reads one card's fields in order, reporting the first problem with its column.
class CardReader {
public:
    CardReader(const std::vector<Token>& t, Diagnostics& d) : t_(t), d_(d) {}
    bool ok() const { return ok_; }
    const Token& keyword() const { return t_[0]; }
    bool more_positional() const { return next_ < t_.size() && !(next_ + 1 < t_.size() && t_[next_ + 1].text == "="); }
    bool at_end() const { return next_ >= t_.size(); }
    const Token* peek() const { return next_ < t_.size() ? &t_[next_] : nullptr; }

    void fail(const Pos& p, std::string m) {
        if (ok_) d_.push_back({p, std::move(m)});
        ok_ = false;
    }
    Pos end_pos() const {
        const Token& l = t_.back();
        return {l.pos.file, l.pos.line, l.pos.col + int(l.text.size())};
    }
    const Token* field(const char* what) {
        if (!ok_) return nullptr;
        if (next_ >= t_.size() || t_[next_].text == "=" || (next_ + 1 < t_.size() && t_[next_ + 1].text == "=")) {
            fail(next_ < t_.size() ? t_[next_].pos : end_pos(), std::string("missing field: ") + what);
            return nullptr;
        }
        return &t_[next_++];
    }
    // A field that is one of `words` (in the order of the enum it picks; `alias` is read as
    // words[1]): its index, or -1 after the error "unknown KIND 'x' (A, B or C)".
    int word_of(const char* kind, std::initializer_list<const char*> words, const char* alias = nullptr) {
        std::string list;
        std::vector<std::string> all;
        for (const char* w : words) {
            if (!all.empty()) list += all.size() + 1 == words.size() ? " or " : ", ";
            list += w;
            all.emplace_back(w);
        }
        const Token* t = field(list.c_str());
        if (!t) return -1;
        const std::string u = upper(t->text);
        for (std::size_t k = 0; k < all.size(); ++k)
            if (u == all[k]) return int(k);
        if (alias && u == alias) return 1;
        fail(t->pos, "unknown " + std::string(kind) + " '" + t->text + "' (" + list + ")" + did_you_mean(t->text, all));
        return -1;
    }
    double real(const char* what) {
        const Token* t = field(what);
        double v = 0;
        if (t && !number(*t, what, v)) return 0;
        return v;
    }
    long integer(const char* what, long lo, long hi) {
        const Token* t = field(what);
        double v = 0;
        if (!t || !number(*t, what, v)) return 0;
        if (v != std::floor(v)) { fail(t->pos, std::string(what) + " must be a whole number, found '" + t->text + "'"); return 0; }
        if (v < double(lo) || v > double(hi)) {
            fail(t->pos, std::string(what) + " must lie in [" + std::to_string(lo) + ", " + std::to_string(hi) + "], found '" + t->text + "'");
            return 0;
        }
        return long(v);
    }
    bool number(const Token& t, const char* what, double& v) {
        bool range = false;
        if (parse_real(t.text, v, &range)) return true;
        const std::string u = upper(t.text);
        if (range)
            fail(t.pos, std::string(what) + ": '" + t.text + "' is out of range for a double");
        else if (u.find("NAN") != std::string::npos || u.find("INF") != std::string::npos)
            fail(t.pos, std::string(what) + ": '" + t.text + "' is not a finite number");
        else
            fail(t.pos, std::string(what) + ": expected a number, found '" + t.text + "'");
        return false;
    }
    // NAME=VALUE parameters; each name at most once, from the allowed list.
    struct Param {
        std::string name;
        double value = 0;
        Pos pos;
    };
    // The positional fields of card (kDeckKeys, in order) into scene object `index` of sc,
    // each checked against its range.
    // With `only`, that field alone.
    void fields(const char* card, Scene& sc, std::size_t index, const char* only = nullptr) {
        for (const DeckKey& k : kDeckKeys) {
            if (k.param || std::strcmp(k.card, card) != 0 || !ok_ || (only && std::strcmp(k.name, only) != 0)) continue;
            const Token* t = peek();
            const double v = k.whole ? double(integer(k.what, long(k.lo), long(k.hi))) : real(k.what);
            if (!ok_) return;
            if (!in_range(k, v)) { fail(t->pos, range_message(k, v)); return; }
            k.set(sc, index, v);
        }
    }
    // The NAME=value parameters of card (of a material model: kElastic, kMohr) into scene
    // object `index` of sc, then each checked against its range, in the order given.
    // `words`: the card's parameters whose values are words, which its own reader took
    // out before (named where an unknown parameter is).
    void parameters(const char* card, int model, Scene& sc, std::size_t index, const std::vector<const char*>& words = {}) {
        std::vector<const char*> allowed, required;
        for (const DeckKey& k : kDeckKeys) {
            if (!k.param || std::strcmp(k.card, card) != 0 || (model && !(k.models & model))) continue;
            allowed.push_back(k.name);
            if (k.required) required.push_back(k.name);
        }
        const std::vector<Param> ps = params(allowed, required, words);
        for (const Param& p : ps) {  // a value out of range is not stored (it may not fit the member)
            const DeckKey& k = *deck_key(card, p.name);
            if (in_range(k, p.value)) k.set(sc, index, p.value);
        }
        for (const Param& p : ps) {
            const DeckKey& k = *deck_key(card, p.name);
            if (ok_ && !key_ok(k, p.value, sc, index)) fail(p.pos, range_message(k, p.value));
        }
    }
    std::vector<Param> params(const std::vector<const char*>& allowed, const std::vector<const char*>& required, const std::vector<const char*>& words = {});
    void finish() {
        if (ok_ && next_ < t_.size()) fail(t_[next_].pos, "extra field '" + t_[next_].text + "'");
    }
    // One NAME=value at the reader (more_positional() false): its two tokens, or false
    // after an error.
    bool one_param(const Token*& name, const Token*& value) {
        if (!ok_ || next_ >= t_.size()) return false;
        name = &t_[next_];
        if (name->text == "=") { fail(name->pos, "'=' without a parameter name"); return false; }
        if (next_ + 2 >= t_.size() || t_[next_ + 2].text == "=") { fail(t_[next_ + 1].pos, "missing value after " + upper(name->text) + "="); return false; }
        value = &t_[next_ + 2];
        next_ += 3;
        return true;
    }

private:
    const std::vector<Token>& t_;
    Diagnostics& d_;
    std::size_t next_ = 1;
    bool ok_ = true;
};

inline std::vector<CardReader::Param> CardReader::params(const std::vector<const char*>& allowed, const std::vector<const char*>& required,
                                                         const std::vector<const char*>& words) {
    std::vector<Param> out;
    while (ok_ && next_ < t_.size()) {
        const Token& name = t_[next_];
        if (name.text == "=") { fail(name.pos, "'=' without a parameter name"); break; }
        if (next_ + 1 >= t_.size() || t_[next_ + 1].text != "=") { fail(name.pos, "extra field '" + name.text + "'"); break; }
        const std::string u = upper(name.text);
        bool known = false;
        for (const char* a : allowed) known |= u == a;
        if (!known) {
            std::vector<std::string> named(allowed.begin(), allowed.end());
            named.insert(named.end(), words.begin(), words.end());
            fail(name.pos, "unknown parameter '" + name.text + "' (this card takes " + joined(named) + ")" + did_you_mean(name.text, named));
            break;
        }
        for (const auto& p : out)
            if (p.name == u) { fail(name.pos, "parameter " + u + " given twice"); break; }
        if (!ok_) break;
        if (next_ + 2 >= t_.size() || t_[next_ + 2].text == "=") { fail(t_[next_ + 1].pos, "missing value after " + u + "="); break; }
        const Token& val = t_[next_ + 2];
        double v = 0;
        if (!number(val, u.c_str(), v)) break;
        out.push_back({u, v, val.pos});
        next_ += 3;
    }
    for (const char* r : required) {
        if (!ok_) break;
        bool have = false;
        for (const auto& p : out) have |= p.name == r;
        if (!have) fail(end_pos(), std::string("missing parameter ") + r + "=");
    }
    return out;
}


}  // namespace detail

// The whole text of a file (what: "deck", "motion file" for the messages), or a diagnostic.

// A SHAKE card's motion file into k.t, k.a: two numbers a line (time [s], acceleration
// [m/s^2]), blanks or commas between, '#' to the end of a line a comment, times from 0 on
// and increasing. Problems are reported at the file's line and column.
LPFDM_DEF Diagnostics read_motion(const std::string& path, Shake& k) {
    std::string text;
    Diagnostics d = load_file(path, text, "motion file");
    if (!d.empty()) return d;
    text = detail::unix_lines(text);  // as a deck: a byte order mark skipped, CR LF or CR ending lines
    int line_no = 0;
    std::size_t at = 0;
    std::string line;
    while (detail::next_line(text, at, line)) {
        ++line_no;
        const std::size_t hash = line.find('#');
        if (hash != std::string::npos) line.resize(hash);
        auto blank = [](char ch) { return ch == ' ' || ch == '\t' || ch == ',' || ch == '\r' || ch == '\f' || ch == '\v'; };
        for (std::size_t c = 0; c < line.size(); ++c) {
            const unsigned char ch = static_cast<unsigned char>(line[c]);
            if ((ch < 0x20 && !blank(char(ch))) || ch == 0x7f)
                return one_error(path, line_no, int(c) + 1, fmt::format("the motion file holds binary data (byte 0x{:02x}); it is plain text", ch));
        }
        std::vector<std::pair<std::string, int>> words;
        for (std::size_t c = 0; c < line.size();) {
            if (blank(line[c])) { ++c; continue; }
            const std::size_t b = c;
            while (c < line.size() && !blank(line[c])) ++c;
            words.push_back({line.substr(b, c - b), int(b) + 1});
        }
        if (words.empty()) continue;
        if (words.size() != 2)
            return one_error(path, line_no, words.size() > 2 ? words[2].second : words[0].second,
                             fmt::format("expected two numbers, time [s] and acceleration [m/s^2]; this line has {}", words.size()));
        double v[2];
        for (int c = 0; c < 2; ++c) {
            bool range = false;
            if (!detail::parse_real(words[std::size_t(c)].first, v[c], &range) || !std::isfinite(v[c]))
                return one_error(path, line_no, words[std::size_t(c)].second,
                                 fmt::format("{}: expected a finite number, found '{}'", c == 0 ? "time" : "acceleration", words[std::size_t(c)].first));
        }
        if (v[0] < 0) return one_error(path, line_no, words[0].second, fmt::format("time {} s is before 0: the record starts at time 0 or later", words[0].first));
        if (!k.t.empty() && !(v[0] > k.t.back()))
            return one_error(path, line_no, words[0].second, fmt::format("time {} s does not come after the line before's {:g} s: times must increase", words[0].first, k.t.back()));
        k.t.push_back(v[0]);
        k.a.push_back(v[1]);
    }
    if (k.t.empty()) return one_error(path, 1, 1, "the motion file holds no samples (two numbers a line: time [s], acceleration [m/s^2])");
    if (k.t.size() < 2) return one_error(path, 1, 1, "the motion file holds one sample; a record needs at least two");
    return {};
}

// The rest of a card `CLUSTER mat POLYGON x1 y1 x2 y2 x3 y3 ...` after its material: the
// numbers up to the parameters, each with its place; a count that makes no polygon is the
// card's error (the shape is validate()'s).
namespace detail {
inline void read_polygon(CardReader& r, Cluster& c) {
    const Token* word = r.field("POLYGON");
    while (r.ok() && r.more_positional()) {
        const std::size_t k = c.polygon.size();
        const std::string what = "vertex " + std::to_string(k / 2 + 1) + (k % 2 ? " y" : " x");
        const Token* t = r.field(what.c_str());
        double v = 0;
        if (t && r.number(*t, what.c_str(), v)) {
            c.polygon.push_back(v);
            c.polygon_pos.push_back(t->pos);
        }
    }
    const std::size_t n = c.polygon.size();
    if (r.ok() && (n % 2 || n < 6 || n / 2 > kMaxPolygonVertices)) {
        std::size_t bad = 0;
        const std::string problem = polygon_problem(c.polygon, bad);
        r.fail(bad < n ? c.polygon_pos[bad] : word->pos, problem);
    }
}
}  // namespace detail

namespace detail {
// The cards that take more than their fields (parse_deck_text): each reads its card with r
// into sc (kp: where the card starts), and takes back what it added when the card fails.
// MATERIAL id ELASTIC|MOHR NAME=value ...
inline void read_material(CardReader& r, Scene& sc, const Pos& kp) {
    sc.materials.emplace_back();
    const std::size_t at = sc.materials.size() - 1;
    sc.materials[at].pos = kp;
    r.fields("MATERIAL", sc, at);
    const Token* model = r.field("model (ELASTIC or MOHR)");
    if (model) {
        const std::string mm = upper(model->text);
        if (mm == "ELASTIC") {
            r.parameters("MATERIAL", kElastic, sc, at);
        } else if (mm == "MOHR") {
            sc.materials[at].model = Model::MohrCoulomb;
            r.parameters("MATERIAL", kMohr, sc, at);
        } else {
            r.fail(model->pos, "unknown material model '" + model->text + "' (ELASTIC or MOHR)");
        }
    }
    if (!r.ok()) sc.materials.pop_back();
}
// CLUSTER mat x0 y0 x1 y1 [PPC=n] [FILL=CELLS|POINTS], or CLUSTER mat POLYGON x1 y1 ...
// [PPC=n] [FILL=CELLS|POINTS]. FILL=, whose value is a word, is taken out of the card's
// tokens and the rest read by a reader of its own; FILL= stands among the parameters,
// after the fields. The card's first problem is reported, FILL's or the rest's. False
// when the card failed.
inline bool read_cluster(Diagnostics& d, Scene& sc, const Pos& kp, const std::vector<Token>& toks) {
    std::vector<Token> kept;
    const Token* fill = nullptr;
    Diagnostic problem;  // FILL's first (no message: none)
    auto fail = [&](const Pos& p, std::string m) { if (problem.message.empty()) problem = {p, std::move(m)}; };
    for (std::size_t t = 0; t < toks.size(); ++t) {
        if (!(t > 0 && upper(toks[t].text) == "FILL" && t + 1 < toks.size() && toks[t + 1].text == "=")) { kept.push_back(toks[t]); continue; }
        if (t + 2 >= toks.size() || toks[t + 2].text == "=") { fail(toks[t + 1].pos, "missing value after FILL="); ++t; continue; }
        if (fill) fail(toks[t].pos, "parameter FILL given twice");
        const std::string u = upper(toks[t + 2].text);
        if (u != "POINTS" && u != "CELLS")
            fail(toks[t + 2].pos, "unknown FILL '" + toks[t + 2].text + "' (CELLS or POINTS)" + did_you_mean(toks[t + 2].text, {"CELLS", "POINTS"}));
        for (std::size_t v = t + 3; v < toks.size(); v += 3)  // only NAME=value after it
            if (!(v + 1 < toks.size() && toks[v + 1].text == "=")) {
                fail(toks[t].pos, "FILL= stands before the field '" + toks[v].text + "': the parameters (PPC=, FILL=) come after the fields");
                break;
            }
        fill = &toks[t + 2];
        t += 2;
    }
    const std::size_t before = d.size();
    CardReader c(kept, d);
    sc.clusters.emplace_back();
    const std::size_t at = sc.clusters.size() - 1;
    sc.clusters[at].pos = kp;
    sc.clusters[at].fill_points = fill && upper(fill->text) == "POINTS";
    if (kept.size() > 2 && upper(kept[2].text) == "POLYGON") {
        c.fields("CLUSTER", sc, at, "MAT");
        detail::read_polygon(c, sc.clusters[at]);
    } else {
        c.fields("CLUSTER", sc, at);
    }
    c.parameters("CLUSTER", 0, sc, at, {"FILL"});
    c.finish();
    if (!problem.message.empty()) {  // FILL's, unless the rest's (the one c reported) comes first
        const Pos& q = problem.pos;
        if (d.size() == before) d.push_back(problem);
        else if (q.line < d.back().pos.line || (q.line == d.back().pos.line && q.col < d.back().pos.col)) d.back() = problem;
    }
    const bool ok = c.ok() && problem.message.empty();
    if (!ok) sc.clusters.pop_back();
    return ok;
}
// FIX X|Y|XY x0 y0 x1 y1
inline void read_fix(CardReader& r, Scene& sc, const Pos& kp) {
    Fix f;
    f.pos = kp;
    const Token* dir = r.field("direction (X, Y or XY)");
    if (dir) {
        const std::string u = upper(dir->text);
        if (u == "X") f.dirs = kFixX;
        else if (u == "Y") f.dirs = kFixY;
        else if (u == "XY" || u == "YX") f.dirs = kFixX | kFixY;
        else r.fail(dir->pos, "unknown direction '" + dir->text + "' (X, Y or XY)");
    }
    sc.fixes.push_back(f);
    r.fields("FIX", sc, sc.fixes.size() - 1);
    if (!r.ok()) sc.fixes.pop_back();
}
// WALL id x0 y0 x1 y1 vx vy [SMOOTH|ROUGH]
inline void read_wall(CardReader& r, Scene& sc, const Pos& kp) {
    sc.walls.emplace_back();
    sc.walls.back().pos = kp;
    r.fields("WALL", sc, sc.walls.size() - 1);
    if (r.ok() && !r.at_end()) {
        const Token* w = r.field("SMOOTH or ROUGH");
        const std::string u = w ? upper(w->text) : std::string();
        if (u == "SMOOTH") sc.walls.back().smooth = true;
        else if (u != "ROUGH" && w) r.fail(w->pos, "unknown word '" + w->text + "' (SMOOTH or ROUGH)" + did_you_mean(w->text, {"SMOOTH", "ROUGH"}));
    }
    if (!r.ok()) sc.walls.pop_back();
}
// SHAKE X|Y FILE=name [SCALE=s] [START=t] [DAMPING=alpha] [COMPLIANT] [BASELINE]
inline void read_shake(CardReader& r, Scene& sc, const Pos& kp, const std::string& file) {
    // SHAKE X|Y FILE=name [SCALE=s] [START=t] [DAMPING=alpha] [COMPLIANT] [BASELINE], the
    // parameters and words in any order after the direction.
    Shake k;
    k.pos = kp;
    const int dir = r.word_of("direction", {"X", "Y"});
    k.dir = dir == 1 ? kFixY : kFixX;
    sc.shakes.push_back(k);
    const std::size_t at = sc.shakes.size() - 1;
    const Token* file_tok = nullptr;
    std::vector<std::string> seen;
    const std::vector<std::string> names = {"FILE", "SCALE", "START", "DAMPING"}, words = {"COMPLIANT", "BASELINE"};
    while (r.ok() && !r.at_end()) {
        if (r.more_positional() && r.peek()->text != "=") {  // a word (a lone '=' goes to one_param, which names it)
            const Token* w = r.field("COMPLIANT or BASELINE");
            if (!w) break;
            const std::string u = upper(w->text);
            if (u != "COMPLIANT" && u != "BASELINE") { r.fail(w->pos, "unknown word '" + w->text + "' (COMPLIANT or BASELINE)" + did_you_mean(w->text, words)); break; }
            if (std::find(seen.begin(), seen.end(), u) != seen.end()) { r.fail(w->pos, u + " given twice"); break; }
            seen.push_back(u);
            (u == "COMPLIANT" ? sc.shakes[at].compliant : sc.shakes[at].baseline) = true;
            continue;
        }
        const Token *n = nullptr, *v = nullptr;
        if (!r.one_param(n, v)) break;
        const std::string u = upper(n->text);
        if (std::find(names.begin(), names.end(), u) == names.end()) {
            r.fail(n->pos, "unknown parameter '" + n->text + "' (this card takes FILE, SCALE, START, DAMPING)" + did_you_mean(n->text, names));
            break;
        }
        if (std::find(seen.begin(), seen.end(), u) != seen.end()) { r.fail(n->pos, "parameter " + u + " given twice"); break; }
        seen.push_back(u);
        if (u == "FILE") { file_tok = v; continue; }
        const DeckKey& key = *deck_key("SHAKE", u.c_str());
        double x = 0;
        if (!r.number(*v, u.c_str(), x)) break;
        if (!in_range(key, x)) { r.fail(v->pos, range_message(key, x)); break; }
        key.set(sc, at, x);
    }
    if (r.ok() && !file_tok) r.fail(r.end_pos(), "missing parameter FILE= (the motion file: time [s] and acceleration [m/s^2] a line)");
    if (r.ok()) {  // the motion file, beside the deck unless its path is absolute
        namespace fs = std::filesystem;
        const fs::path name(file_tok->text);
        const std::string path = name.is_absolute() ? name.string() : (fs::path(file).parent_path() / name).string();
        sc.shakes[at].file = file_tok->text;
        Diagnostics md = read_motion(path, sc.shakes[at]);
        if (!md.empty()) {
            if (md[0].pos.line == 0) {  // the file itself: at the card, naming the path tried
                md[0].pos = file_tok->pos;
                const std::string the = "the motion file";
                const std::size_t named = md[0].message.find(the);
                if (named != std::string::npos) md[0].message.insert(named + the.size(), " '" + path + "'");
                if (!name.is_absolute()) md[0].message += " (a relative FILE= is read from the deck's directory)";
            }
            r.fail(md[0].pos, md[0].message);
        }
    }
    if (!r.ok()) sc.shakes.pop_back();
}
// WATER [KW=] [RHOW=] [TABLE=] [UNDRAINED], the word anywhere on the card: read from its
// tokens without the word (r: the card's reader, for the word's own errors).
inline void read_water(const std::vector<Token>& toks, Diagnostics& d, Scene& sc, const Pos& kp, CardReader& r) {
    std::vector<Token> kept;
    bool undrained = false;
    for (std::size_t t = 0; t < toks.size(); ++t) {
        const bool word = t > 0 && upper(toks[t].text) == "UNDRAINED" && !(t + 1 < toks.size() && toks[t + 1].text == "=");
        if (!word) { kept.push_back(toks[t]); continue; }
        if (undrained) r.fail(toks[t].pos, "UNDRAINED is given twice");
        undrained = true;
    }
    if (!r.ok()) return;
    CardReader w(kept, d);
    sc.water.on = true;
    sc.water.pos = kp;
    sc.water.undrained = undrained;
    w.parameters("WATER", 0, sc, 0);
    w.finish();
}
// DRAIN x0 y0 x1 y1, LOAD x0 y0 x1 y1 [TX=] [TY=]
inline void read_drain_or_load(CardReader& r, Scene& sc, const Pos& kp, bool load) {
    if (load) {
        sc.loads.emplace_back();
        sc.loads.back().pos = kp;
        r.fields("LOAD", sc, sc.loads.size() - 1);
        r.parameters("LOAD", 0, sc, sc.loads.size() - 1);
        if (!r.ok()) sc.loads.pop_back();
        return;
    }
    sc.drains.emplace_back();
    sc.drains.back().pos = kp;
    r.fields("DRAIN", sc, sc.drains.size() - 1);
    if (!r.ok()) sc.drains.pop_back();
}
// ABSORB BOTTOM|TOP|LEFT|RIGHT ... and OUTFLOW BOTTOM|TOP|LEFT|RIGHT ...: the edges into
// edges (kBottom | kTop | kLeft | kRight), the first card's place into at.
inline void read_edges(CardReader& r, const char* card, int& edges, Pos& at, const Pos& kp) {
    const int before = edges;
    if (!edges) at = kp;
    do {
        const int e = r.word_of("edge", {"BOTTOM", "TOP", "LEFT", "RIGHT"});
        if (e < 0) break;
        const int bit = 1 << e;
        static const char* const edge_names[] = {"BOTTOM", "TOP", "LEFT", "RIGHT"};
        if (edges & bit) { r.fail(kp, std::string(card) + " " + edge_names[e] + " is given twice"); break; }
        edges |= bit;
    } while (r.ok() && !r.at_end());
    if (!r.ok()) edges = before;
}
// OUTPUT POINTS|HISTORY|VTU|STATE file [BINARY] [NODES] [EVERY n]
inline void read_output(CardReader& r, Scene& sc, const Pos& kp) {
    Output o;
    o.pos = kp;
    const Token* kind = r.field("kind (POINTS, HISTORY, VTU or STATE)");
    if (kind) {
        const std::string u = upper(kind->text);
        if (u == "POINTS") o.kind = Output::Points;
        else if (u == "HISTORY") o.kind = Output::History;
        else if (u == "VTU") o.kind = Output::Vtu;
        else if (u == "STATE") o.kind = Output::State;
        else r.fail(kind->pos, "unknown output '" + kind->text + "' (POINTS, HISTORY, VTU or STATE)" +
                                   did_you_mean(kind->text, {"POINTS", "HISTORY", "VTU", "STATE"}));
    }
    const Token* f = r.field("file name");
    if (f) o.file = f->text;
    if (f && (o.file.find('/') != std::string::npos || o.file == "." || o.file == ".."))
        r.fail(f->pos, "the file name must not contain a directory (use -o DIR)");
    // OUTPUT VTU name [BINARY] [NODES], in either order
    while (r.ok() && r.more_positional() && (upper(r.peek()->text) == "BINARY" || upper(r.peek()->text) == "NODES")) {
        const Token* b = r.field("BINARY or NODES");
        const bool binary = upper(b->text) == "BINARY";
        if (o.kind != Output::Vtu) r.fail(b->pos, upper(b->text) + " is a word of OUTPUT VTU only" + (binary ? " (point tables and histories are text)" : ""));
        else if (binary ? o.binary : o.nodes) r.fail(b->pos, upper(b->text) + " given twice");
        else (binary ? o.binary : o.nodes) = true;
    }
    for (const auto& prev : sc.outputs)
        if (r.ok() && prev.file == o.file) r.fail(f->pos, "file '" + o.file + "' is written by another OUTPUT card");
    sc.outputs.push_back(o);
    const std::size_t at = sc.outputs.size() - 1;
    if (r.ok() && !r.at_end()) {
        const Token* e = r.peek();
        if (upper(e->text) == "EVERY" && !r.more_positional()) {  // EVERY=n, like other parameters
            r.parameters("OUTPUT", 0, sc, at);
        } else {  // EVERY n
            e = r.field("EVERY");
            if (e && upper(e->text) != "EVERY") r.fail(e->pos, "extra field '" + e->text + "'");
            const DeckKey& k = *deck_key("OUTPUT", "EVERY");
            const long n = r.integer(k.what, long(k.lo), long(k.hi));
            if (r.ok()) k.set(sc, at, double(n));
        }
    }
    if (!r.ok()) sc.outputs.pop_back();
}
}  // namespace detail

// Parses a deck (decks/README.md) into scene: every card, field and parameter checked, each
// problem reported with file:line:column (the first problem of each card). The scene as a
// whole is checked by validate(), told by *unread what the cards with errors left out.
LPFDM_DEF Diagnostics parse_deck_text(const std::string& text, const std::string& file, Scene& sc, Unread* unread) {
    using namespace detail;
    Diagnostics d;
    Unread none;
    Unread& u = unread ? *unread : none;
    u = Unread();
    if (text.find_first_not_of(" \t\r\n\f\v") == std::string::npos) {
        u.all();
        return one_error(file, 1, 1, "the deck is empty");
    }
    Lexed lx = lex(text, file, d);
    if (!d.empty()) {  // not text, or its last card cut: nothing is read
        u.all();
        return d;
    }
    bool have_grid = false, have_step = false, have_end = false, have_gravity = false, have_damping = false, have_seed = false, have_title = false, have_motion = false, have_mapping = false, have_hourglass = false, have_advect = false, have_reorder = false, have_water = false, have_reservoir = false, have_geostatic = false, have_shift = false;
    Pos last{file, 1, 1};
    int cluster_cards = 0;
    // The cards with errors leave unchecked what depends on them (Unread); an unknown card
    // counts as the card it is nearest to (misspelt), and one near none as a MATERIAL.
    std::vector<std::string> misspelt;  // the cards the unknown cards are nearest to
    auto unread_card = [&](const std::string& card) {
        u.grid |= card == "GRID";
        u.step |= card == "STEP";
        u.materials |= card == "MATERIAL";
        u.clusters |= card == "CLUSTER";
        u.motion |= card == "MOTION" || card == "ADVECT";
        u.mapping |= card == "MAPPING";
        u.fixes |= card == "FIX";
    };
    for (std::size_t ci = 0; ci < lx.cards.size() && !have_end; ++ci) {
        const auto& toks = lx.cards[ci];
        CardReader r(toks, d);
        const std::string kw = upper(toks[0].text);
        const Pos kp = toks[0].pos;
        last = kp;
        auto once = [&](bool& seen) {
            if (seen) r.fail(kp, kw + " is given twice");
            seen = true;
        };
        if (kw == "TITLE") {
            once(have_title);
            sc.title = trimmed(lx.raw[ci], " \t,");
            continue;
        } else if (kw == "GRID") {
            once(have_grid);
            sc.grid_pos = kp;
            r.fields("GRID", sc, 0);
        } else if (kw == "MATERIAL") {
            read_material(r, sc, kp);
        } else if (kw == "CLUSTER") {
            ++cluster_cards;
            if (!read_cluster(d, sc, kp, toks)) unread_card(kw);
            continue;
        } else if (kw == "FIX") {
            read_fix(r, sc, kp);
        } else if (kw == "WALL") {
            read_wall(r, sc, kp);
        } else if (kw == "SHAKE") {
            read_shake(r, sc, kp, file);
        } else if (kw == "ABSORB") {
            read_edges(r, "ABSORB", sc.absorb, sc.absorb_pos, kp);
        } else if (kw == "OUTFLOW") {
            read_edges(r, "OUTFLOW", sc.outflow, sc.outflow_pos, kp);
        } else if (kw == "WATER") {
            once(have_water);
            if (r.ok()) read_water(toks, d, sc, kp, r);
            continue;
        } else if (kw == "RESERVOIR") {
            once(have_reservoir);
            sc.reservoir.on = true;
            sc.reservoir.pos = kp;
            r.fields("RESERVOIR", sc, 0);
            r.parameters("RESERVOIR", 0, sc, 0);
        } else if (kw == "SHIFT" || kw == "GEOSTATIC") {  // a switch with parameters only
            const bool shift = kw == "SHIFT";
            once(shift ? have_shift : have_geostatic);
            (shift ? sc.shift : sc.geostatic) = true;
            (shift ? sc.shift_pos : sc.geostatic_pos) = kp;
            r.parameters(kw.c_str(), 0, sc, 0);
        } else if (kw == "DRAIN" || kw == "LOAD") {
            read_drain_or_load(r, sc, kp, kw == "LOAD");
        } else if (kw == "GRAVITY") {
            once(have_gravity);
            r.fields("GRAVITY", sc, 0);
        } else if (kw == "DAMPING") {
            once(have_damping);
            sc.damping_pos = kp;
            r.fields("DAMPING", sc, 0);
            r.parameters("DAMPING", 0, sc, 0);
        } else if (kw == "SEED") {
            once(have_seed);
            r.fields("SEED", sc, 0);
        } else if (kw == "STEP") {
            once(have_step);
            sc.step_pos = kp;
            r.fields("STEP", sc, 0);
        } else if (kw == "OUTPUT") {
            read_output(r, sc, kp);
        } else if (kw == "TRACK") {
            sc.tracks.emplace_back();
            sc.tracks.back().pos = kp;
            r.fields("TRACK", sc, sc.tracks.size() - 1);
            if (!r.ok()) sc.tracks.pop_back();
        } else if (kw == "HOURGLASS") {
            once(have_hourglass);
            r.fields("HOURGLASS", sc, 0);
        } else if (kw == "REORDER") {
            once(have_reorder);
            r.fields("REORDER", sc, 0);
        } else if (kw == "MAPPING") {
            once(have_mapping);
            sc.mapping_pos = kp;
            const int k = r.word_of("mapping", {"PAPER", "SMOOTH"});
            if (k >= 0) sc.mapping = Mapping(k);
        } else if (kw == "MOTION") {
            once(have_motion);
            const int k = r.word_of("motion", {"PAPER", "CENTRE", "BILINEAR"}, "CENTER");
            if (k >= 0) sc.motion = Motion(k);
        } else if (kw == "ADVECT") {
            once(have_advect);
            sc.advect_pos = kp;
            const int k = r.word_of("advection", {"EQ12", "POINTS", "FLIP"});
            if (k >= 0) sc.advect = Advect(k);
        } else if (kw == "END") {
            have_end = true;
            sc.end_pos = kp;
        } else {
            const std::string meant = nearest_name(toks[0].text, card_names());
            r.fail(kp, "unknown card '" + toks[0].text + "'" + (meant.empty() ? "" : " (did you mean " + meant + "?)"));
            misspelt.push_back(meant);
            unread_card(meant.empty() ? "MATERIAL" : meant);  // (a MATERIAL misspelt: its clusters are not "undefined")
            continue;
        }
        r.finish();
        if (!r.ok()) unread_card(kw);
    }
    u.grid |= !have_grid;
    u.step |= !have_step;
    u.clusters |= cluster_cards == 0;
    // A card missing from the whole deck, after the last card (after every card that may
    // have caused it); not when an unknown card is nearest to it: that card is the problem.
    auto no_card_near = [&](const char* card) { return std::find(misspelt.begin(), misspelt.end(), card) == misspelt.end(); };
    if (!have_grid && no_card_near("GRID")) d.push_back({last, "no GRID card: the lattice is not defined"});
    if (!have_step && no_card_near("STEP")) d.push_back({last, "no STEP card: the time step and the number of steps are not defined"});
    if (have_grid && cluster_cards == 0 && no_card_near("CLUSTER")) d.push_back({last, "no CLUSTER card: the scene holds no material"});
    return d;
}

// parse_deck_text and validate() in one pass, every error in the order of the deck: an
// empty result means the scene can run. (Warnings are apart: warnings(sc).)
LPFDM_DEF Diagnostics read_deck_text(const std::string& text, const std::string& file, Scene& sc) {
    Unread unread;
    Diagnostics d = parse_deck_text(text, file, sc, &unread);
    const Diagnostics v = validate(sc, unread);
    d.insert(d.end(), v.begin(), v.end());
    sort_diagnostics(d);
    return d;
}

// The whole text of a file, or a diagnostic.
LPFDM_DEF Diagnostics load_file(const std::string& path, std::string& text, const char* what) {
    const std::string the = std::string("the ") + what;
    // A deck is a regular file of reasonable size: /dev/zero or a pipe that never ends
    // must not hang the program or exhaust memory.
    constexpr std::uintmax_t kMaxDeckBytes = 64u << 20;
    std::error_code ec;
    const auto st = std::filesystem::status(path, ec);
    if (!ec && std::filesystem::is_directory(st)) return one_error(path, 0, 0, "cannot read " + the + ": it is a directory");
    if (!ec && !std::filesystem::is_regular_file(st)) return one_error(path, 0, 0, "cannot read " + the + ": it is not a regular file");
    if (!ec && std::filesystem::file_size(path, ec) > kMaxDeckBytes && !ec)
        return one_error(path, 0, 0, the + " is larger than 64 MiB; a " + what + " is a short text");
    std::ifstream in(path, std::ios::binary);
    {  // a directory opens as a stream and reads as empty: ask for one byte to tell
        std::FILE* f = std::fopen(path.c_str(), "rb");
        if (f) {
            char b;
            const std::size_t got = std::fread(&b, 1, 1, f);
            const bool err = got == 0 && std::ferror(f);
            const int e = errno;
            std::fclose(f);
            if (err) return one_error(path, 0, 0, "cannot read " + the + ": " + (e == EISDIR ? "it is a directory" : std::strerror(e)));
        }
    }
    if (!in) return one_error(path, 0, 0, "cannot open " + the + ": " + std::strerror(errno));
    std::ostringstream ss;
    ss << in.rdbuf();
    if (in.bad()) return one_error(path, 0, 0, "cannot read " + the);
    text = ss.str();
    return {};
}

LPFDM_DEF Diagnostics read_deck(const std::string& path, Scene& sc) {
    std::string text;
    Diagnostics d = load_file(path, text);
    return d.empty() ? read_deck_text(text, path, sc) : d;
}

// -------------------------------------------------------------- writers ---

// FNV-1a, 64 bits: the digest of a deck's text recorded in the output headers.
LPFDM_DEF std::uint64_t fnv1a64(const std::string& text) {
    std::uint64_t h = 14695981039346656037ull;
    for (unsigned char ch : text) { h ^= ch; h *= 1099511628211ull; }
    return h;
}
LPFDM_DEF bool read_number(const std::string& text, double& out) { return detail::parse_real(text, out); }


// The provenance lines of each output file (after its names line), each beginning "# run: ": the version, the deck
// and the digest of its text, what the command line changed, and the seed, steps, threads
// and kernel the run used. Only the threads and kernel lines differ between runs that
// write the same numbers: comparisons of outputs skip these lines (grep -v '^# run: ').
LPFDM_DEF void write_provenance(std::FILE* f, const Simulation& sim, const RunInfo& r) {
    std::string deck = r.deck;
    for (char& ch : deck) if (ch == '\n' || ch == '\r') ch = '?';
    std::string cl;
    if (r.steps > 0) cl += fmt::format(" --steps {}", r.steps);
    if (r.refine > 1) cl += fmt::format(" --refine {}", r.refine);
    if (r.seed >= 0) cl += fmt::format(" --seed {}", r.seed);
    for (const std::string& kv : r.settings) cl += " --set " + kv;
    fmt::print(f, "# run: lpfdm {}\n# run: deck {} (fnv1a64 {:016x})\n", kVersion, deck, r.deck_digest);
    fmt::print(f, "# run: options{}\n", cl.empty() ? " (none)" : cl);
    fmt::print(f, "# run: seed {} steps {} dt {:.9g} s\n", sim.scene().seed, sim.scene().steps, sim.scene().dt_s);
    fmt::print(f, "# run: threads {} kernel {}\n", r.threads, r.kernel);
}

// The column names of a point table and of a history, on the first line of each: a line
// without '#', so that numpy.genfromtxt(names=True), pandas.read_csv(sep=r"\s+",
// comment="#") and gnuplot's columnheader take their names from it (every other line
// of a header is a '#' comment; the names are repeated there).
LPFDM_DEF std::string history_columns(const Simulation& sim) {
    std::string h = "step time ke mass_in mass_out";
    for (const auto& w : sim.scene().walls) h += fmt::format(" w{0}_fx w{0}_fy w{0}_dx w{0}_dy", w.id);
    h += " unbal rx ry";
    for (std::size_t a = 0; a < sim.scene().fixes.size(); ++a) h += fmt::format(" f{0}_rx f{0}_ry", a + 1);
    h += " e_kin e_strain e_grav w_walls w_fixes w_gravity d_damping d_plastic energy_error parked packed";
    if (sim.dynamic()) h += " w_ground d_absorb ground_dx ground_dy";  // SHAKE, ABSORB
    for (std::size_t t = 0; t < sim.tracked().size(); ++t) h += fmt::format(" t{0}_x t{0}_y t{0}_ux t{0}_uy", t + 1);  // TRACK
    if (sim.loaded()) h += " w_loads";                     // LOAD, RESERVOIR
    if (sim.scene().reservoir.on) h += " level";            // RESERVOIR
    if (sim.water()) h += " d_water p_excess drained";      // WATER
    if (sim.scene().advect == Advect::Flip) h += " d_slip";  // ADVECT FLIP
    if (sim.scene().shift) h += " w_shift shifted";          // SHIFT
    return h;
}

// Point table: one frame; frames are separated by two blank lines.
// run: the provenance lines, after the names line (nullptr: none).
LPFDM_DEF void write_points_header(std::FILE* f, const Simulation& sim, const std::string& deck, const RunInfo* run) {
    const std::string columns = std::string(kPointColumns) + (sim.water() ? " p" : "");  // WATER: the pore pressure last
    fmt::print(f, "{}\n", columns);
    if (run) write_provenance(f, sim, *run);
    fmt::print(f, "# lpfdm {} point table\n# deck: {}\n# title: {}\n", kVersion, deck, sim.scene().title);
    fmt::print(f, "# units: m, Pa (tension positive); lattice {} x {} cells of {} m\n", sim.mx(), sim.my(), sim.cell_size());
    fmt::print(f, "# columns: {}\n", columns);
    fmt::print(f, "#   ep = accumulated plastic shear strain |d_eps1^p - d_eps3^p|; yielded = 1 once the point has yielded (softened)\n");
    fmt::print(f, "#   ux uy = displacement since step 0 [m]\n");
    if (sim.water()) fmt::print(f, "#   sxx syy sxy szz are effective stresses; p = pore pressure [Pa, compression positive]: the total stress is sigma - p I\n");
}

LPFDM_DEF void write_points_frame(std::FILE* f, const Simulation& sim, bool first) {
    const Points& p = sim.points();
    fmt::memory_buffer b;
    if (!first) fmt::format_to(std::back_inserter(b), "\n\n");
    fmt::format_to(std::back_inserter(b), "# step {} time {:.9g}\n", sim.step_count(), sim.time());
    const bool plastic = !p.plastic_shear.empty(), water = sim.water();
    for (const std::int32_t slot : sim.by_id()) {  // by id, whatever the storage order (REORDER)
        const std::size_t k = std::size_t(slot);
        const std::size_t id = std::size_t(p.id[k]);
        fmt::format_to(std::back_inserter(b), FMT_COMPILE("{:.9g} {:.9g} {:.7g} {:.7g} {:.7g} {:.7g} {:.6g} {} {} {} {:.7g} {:.7g}\n"), p.x[k], p.y[k], p.sxx[k], p.syy[k],
                       p.sxy[k], p.szz[k], plastic ? p.plastic_shear[k] : 0.0, plastic ? int(p.yielded[k]) : 0, sim.material_id(k), p.id[k],
                       p.x[k] - sim.initial_x()[id], p.y[k] - sim.initial_y()[id]);
        if (water) { b.resize(b.size() - 1); fmt::format_to(std::back_inserter(b), FMT_COMPILE(" {:.7g}\n"), p.pw[k]); }
        if (b.size() > (1 << 20)) { std::fwrite(b.data(), 1, b.size(), f); b.clear(); }
    }
    std::fwrite(b.data(), 1, b.size(), f);
}

// History: step time ke mass_in mass_out, per wall fx fy dx dy, then more.
LPFDM_DEF void write_history_header(std::FILE* f, const Simulation& sim, const std::string& deck, const RunInfo* run) {
    const std::string h = history_columns(sim);
    fmt::print(f, "{}\n", h);
    if (run) write_provenance(f, sim, *run);
    fmt::print(f, "# lpfdm {} history\n# deck: {}\n# title: {}\n", kVersion, deck, sim.scene().title);
    fmt::print(f, "# units: s, J/m, kg/m, N/m, m; wall force = force the wall exerts on the material\n");
    fmt::print(f, "# unbal = max unbalanced nodal force / mean gross nodal force (free directions); rx ry = reactions of the fixed nodes,\n");
    fmt::print(f, "#   f<n>_rx f<n>_ry = those of FIX card n (deck order; a node held by several cards counts for the first)\n");
    fmt::print(f, "#   energy [J/m] since the start (Simulation::energy): e_kin kinetic (leapfrog), e_strain elastic, e_grav potential of the points;\n");
    fmt::print(f, "#   w_walls w_fixes w_gravity work done on the material; d_damping d_plastic dissipated;\n");
    fmt::print(f, "#   energy_error = (work in - stored - dissipated) / (energy in play), work in = w_walls + w_fixes{}\n", sim.dynamic() ? " + w_ground" : "");
    fmt::print(f, "#   parked = points stopped on a fixed edge or a wall's face since step 0 (their moves clamped)\n");
    fmt::print(f, "#   packed = the most volume one cell's points hold over the cell's area (eq. 8's sum of V / L^2, the step's largest)\n");
    if (sim.dynamic())
        fmt::print(f, "#   w_ground work of the ground motion (SHAKE), d_absorb taken out by the dashpots (ABSORB); ground_dx ground_dy the ground's displacement [m]\n");
    if (sim.loaded()) fmt::print(f, "#   w_loads work of the LOAD tractions and the RESERVOIR's pressure (counted as work in)\n");
    if (sim.scene().reservoir.on) fmt::print(f, "#   level the RESERVOIR's surface [m]\n");
    if (sim.water())
        fmt::print(f, "#   d_water stored water energy the flow and the drains took out (dissipated); p_excess the largest pore pressure above hydrostatic [Pa]; drained water out through DRAIN [m^3/m]\n");
    if (sim.scene().advect == Advect::Flip)
        fmt::print(f, "#   d_slip (ADVECT FLIP) dissipated by the slip between a support that changes speed (SHAKE's ground, a wall's new velocity) and the material beside it\n");
    if (sim.scene().shift)
        fmt::print(f, "#   w_shift (SHIFT) the potential energy the points' moves apart gave them (counted as work in); shifted the point moves since step 0\n");
    fmt::print(f, "# {}\n", h);
}

LPFDM_DEF void write_history_row(std::FILE* f, const Simulation& sim) {
    fmt::memory_buffer b;
    fmt::format_to(std::back_inserter(b), "{} {:.9g} {:.9g} {:.17g} {:.17g}", sim.step_count(), sim.time(), sim.kinetic_energy(), sim.mass_inside(),
                   sim.mass_outflow());
    for (const auto& w : sim.walls()) fmt::format_to(std::back_inserter(b), " {:.9g} {:.9g} {:.9g} {:.9g}", w.fx, w.fy, w.dx, w.dy);
    fmt::format_to(std::back_inserter(b), " {:.6g} {:.9g} {:.9g}", sim.unbalanced_ratio(), sim.reaction_x(), sim.reaction_y());
    for (std::size_t a = 0; a < sim.scene().fixes.size(); ++a) fmt::format_to(std::back_inserter(b), " {:.9g} {:.9g}", sim.fix_reaction_x(a), sim.fix_reaction_y(a));
    const Simulation::Energy e = sim.energy();
    fmt::format_to(std::back_inserter(b), " {:.9g} {:.9g} {:.9g} {:.9g} {:.9g} {:.9g} {:.9g} {:.9g} {:.6g} {} {:.6g}", e.kinetic, e.strain, e.gravity, e.w_walls,
                   e.w_fixes, e.w_gravity, e.d_damping, e.d_plastic, e.error, sim.parked(), sim.packing());
    if (sim.dynamic())
        fmt::format_to(std::back_inserter(b), " {:.9g} {:.9g} {:.9g} {:.9g}", e.w_ground, e.d_absorb, sim.ground_displacement(0), sim.ground_displacement(1));
    for (const std::int32_t id : sim.tracked()) {  // TRACK: the point's place and displacement (nan once it left the lattice)
        const long k = id < 0 ? -1 : sim.slot_of(id);
        const double nan = std::numeric_limits<double>::quiet_NaN();
        const double x = k < 0 ? nan : sim.points().x[std::size_t(k)], y = k < 0 ? nan : sim.points().y[std::size_t(k)];
        const double ux = k < 0 ? nan : x - sim.initial_x()[std::size_t(id)], uy = k < 0 ? nan : y - sim.initial_y()[std::size_t(id)];
        fmt::format_to(std::back_inserter(b), " {:.9g} {:.9g} {:.7g} {:.7g}", x, y, ux, uy);
    }
    if (sim.loaded()) fmt::format_to(std::back_inserter(b), " {:.9g}", e.w_loads);
    if (sim.scene().reservoir.on) fmt::format_to(std::back_inserter(b), " {:.9g}", sim.scene().reservoir.at(sim.time()));
    if (sim.water()) fmt::format_to(std::back_inserter(b), " {:.9g} {:.9g} {:.9g}", e.d_water, sim.excess_pressure(), sim.drained());
    if (sim.scene().advect == Advect::Flip) fmt::format_to(std::back_inserter(b), " {:.9g}", e.d_slip);
    if (sim.scene().shift) fmt::format_to(std::back_inserter(b), " {:.9g} {}", e.w_shift, sim.shifted());
    b.push_back('\n');
    std::fwrite(b.data(), 1, b.size(), f);
}

// VTK XML files (ParaView, VisIt), written without the VTK library.
namespace detail {
// A data array of a VTK XML file: its name, VTK type, components, and value(k, component)
// of tuple k.
struct VtkArray {
    enum Type { F64, I32, U8, I64 } type;
    const char* name;
    int comps;
    std::function<double(std::size_t, int)> value;
};
// Writes a VTK XML file: text() for the elements, array() for each DataArray (its values
// inline as ASCII, or, binary, as raw bytes in the AppendedData block that finish()
// writes, each behind its byte count, UInt64), finish() for the end.
class VtkXml {
public:
    VtkXml(std::FILE* f, bool binary) : f_(f), binary_(binary) {}
    void text(const std::string& s) { b_.append(s.data(), s.data() + s.size()); }
    // <VTKFile type="..."> in this machine's byte order.
    void open(const char* type) {
        const std::uint16_t one = 1;
        const bool little = *reinterpret_cast<const unsigned char*>(&one) == 1;
        text(fmt::format("<?xml version=\"1.0\"?>\n<VTKFile type=\"{}\" version=\"1.0\" byte_order=\"{}\" header_type=\"UInt64\">\n", type,
                         little ? "LittleEndian" : "BigEndian"));
    }
    // The frame's time and step, as FieldData (TimeValue: VTK's name for the time).
    void time(double t, long step) {
        text(fmt::format("    <FieldData>\n      <DataArray type=\"Float64\" Name=\"TimeValue\" NumberOfTuples=\"1\" format=\"ascii\">{:.15g}</DataArray>\n", t));
        text(fmt::format("      <DataArray type=\"Int64\" Name=\"STEP\" NumberOfTuples=\"1\" format=\"ascii\">{}</DataArray>\n    </FieldData>\n", step));
    }
    void array(const VtkArray& a, std::size_t n, const char* indent) {
        text(fmt::format("{}<DataArray type=\"{}\" Name=\"{}\" NumberOfComponents=\"{}\" format=\"{}\"", indent, kTypeName[a.type], a.name, a.comps,
                         binary_ ? "appended" : "ascii"));
        if (binary_) {
            text(fmt::format(" offset=\"{}\"/>\n", offset_));
            offset_ += 8 + std::uint64_t(n) * std::uint64_t(a.comps) * kTypeSize[a.type];
            appended_.push_back({&a, n});
            return;
        }
        text(">\n");
        auto out = std::back_inserter(b_);
        for (std::size_t k = 0; k < n; ++k) {
            for (int c = 0; c < a.comps; ++c) {
                const double v = a.value(k, c);
                if (a.type == VtkArray::F64) fmt::format_to(out, "{}{:.9g}", c ? " " : "", v);
                else fmt::format_to(out, "{}{}", c ? " " : "", std::int64_t(v));
            }
            b_.push_back('\n');
            if (b_.size() > (1 << 20)) flush();
        }
        text(fmt::format("{}</DataArray>\n", indent));
    }
    void finish() {
        if (binary_) {
            text("  <AppendedData encoding=\"raw\">\n   _");
            for (const auto& ap : appended_) {
                const VtkArray& a = *ap.first;
                const std::size_t n = ap.second;
                const std::uint64_t bytes = std::uint64_t(n) * std::uint64_t(a.comps) * kTypeSize[a.type];
                raw(&bytes, sizeof bytes);
                for (std::size_t k = 0; k < n; ++k) {
                    for (int c = 0; c < a.comps; ++c) {
                        const double v = a.value(k, c);
                        if (a.type == VtkArray::F64) raw(&v, 8);
                        else if (a.type == VtkArray::I64) { const std::int64_t i = std::int64_t(v); raw(&i, 8); }
                        else if (a.type == VtkArray::I32) { const std::int32_t i = std::int32_t(v); raw(&i, 4); }
                        else { const std::uint8_t i = std::uint8_t(v); raw(&i, 1); }
                    }
                    if (b_.size() > (1 << 20)) flush();
                }
            }
            text("\n  </AppendedData>\n");
        }
        text("</VTKFile>\n");
        flush();
    }

private:
    static constexpr const char* kTypeName[] = {"Float64", "Int32", "UInt8", "Int64"};
    static constexpr std::size_t kTypeSize[] = {8, 4, 1, 8};
    void raw(const void* v, std::size_t bytes) {
        const char* c = static_cast<const char*>(v);
        b_.append(c, c + bytes);
    }
    void flush() { std::fwrite(b_.data(), 1, b_.size(), f_); b_.clear(); }
    std::FILE* f_;
    bool binary_;
    fmt::memory_buffer b_;
    std::uint64_t offset_ = 0;  // of the next array in the appended block
    std::vector<std::pair<const VtkArray*, std::size_t>> appended_;
};
}  // namespace detail

// One frame of the points as a VTK XML UnstructuredGrid of vertex cells, with every
// point field as PointData:
//   stress        sxx sxy 0 / sxy syy 0 / 0 0 szz, the full 3 x 3 tensor (9 components) [Pa]
//   ep, yielded   accumulated plastic shear strain, 1 once yielded (0 without Mohr-Coulomb)
//   material, id  material id, point number (stable across frames)
//   velocity      what the point moves in the next step (its cell's motion rule applied to
//                 the nodal increments) over dt: the velocity at t + dt/2 [m/s]
//   displacement  position minus the position at step 0 (x0, y0: by point id) [m]
// binary: the arrays as raw bytes in an AppendedData block, else ASCII with the point
// table's digits. z is 0.
LPFDM_DEF void write_vtu(std::FILE* f, const Simulation& sim, const std::vector<double>& x0, const std::vector<double>& y0, bool binary) {
    using detail::VtkArray;
    const Points& p = sim.points();
    const std::size_t n = p.size();
    const std::vector<std::int32_t>& order = sim.by_id();  // the points listed by id
    const bool plastic = !p.plastic_shear.empty();
    const int mx = sim.mx();
    const double L = sim.cell_size(), dt = sim.scene().dt_s;
    const std::vector<double>&ux = sim.du_x(), &uy = sim.du_y();
    // The point's increment in the next step, as the point pass makes it (eq. 7a/7b or the
    // scene's MOTION), without the stop at a fixed cell edge.
    auto step_of = [&](std::size_t k, double& dx, double& dy) {
        const int c = p.cell[std::size_t(k)], ci = c % mx, cj = c / mx;
        const StrainIncrement e = sim.strain_of_cell(ci, cj);
        const int n1 = sim.node(ci, cj), n2 = n1 + 1, n3 = n1 + mx + 1, n4 = n3 + 1;
        const double ax[4] = {ux[std::size_t(n1)], ux[std::size_t(n2)], ux[std::size_t(n3)], ux[std::size_t(n4)]};
        const double ay[4] = {uy[std::size_t(n1)], uy[std::size_t(n2)], uy[std::size_t(n3)], uy[std::size_t(n4)]};
        const double xi = ci * L, yj = cj * L;
        double x = 0, y = 0, ddx = 0, ddy = 0;
        if (sim.scene().motion == Motion::Paper) {
            move_point_paper(p.x[k], p.y[k], e, xi, yj, ax[0], ay[0], x, y);
        } else if (sim.scene().motion == Motion::Centre) {
            double umx, umy;
            mean_of_four(ax[0], ax[1], ax[2], ax[3], umx); mean_of_four(ay[0], ay[1], ay[2], ay[3], umy);
            move_point_centre(p.x[k], p.y[k], e, xi, yj, L, umx, umy, x, y, ddx, ddy);
        } else {
            move_point_bilinear(p.x[k], p.y[k], xi, yj, 1 / L, ax, ay, x, y, ddx, ddy);
        }
        dx = x - p.x[k]; dy = y - p.y[k];
    };
    auto origin = [&](const std::vector<double>& v0, std::size_t k) {
        const std::size_t id = std::size_t(p.id[k]);
        return id < v0.size() ? v0[id] : 0.0;
    };
    const VtkArray point_data[] = {
        {VtkArray::F64, "stress", 9, [&](std::size_t r, int c) { const std::size_t k = std::size_t(order[r]);
             const double t[9] = {p.sxx[k], p.sxy[k], 0, p.sxy[k], p.syy[k], 0, 0, 0, p.szz[k]};
             return t[c];
         }},
        {VtkArray::F64, "ep", 1, [&](std::size_t r, int) { const std::size_t k = std::size_t(order[r]); return plastic ? p.plastic_shear[k] : 0.0; }},
        {VtkArray::U8, "yielded", 1, [&](std::size_t r, int) { const std::size_t k = std::size_t(order[r]); return plastic ? double(p.yielded[k]) : 0.0; }},
        {VtkArray::I32, "material", 1, [&](std::size_t r, int) { const std::size_t k = std::size_t(order[r]); return double(sim.material_id(k)); }},
        {VtkArray::F64, "velocity", 3, [&](std::size_t r, int c) { const std::size_t k = std::size_t(order[r]);
             if (c == 2) return 0.0;
             double dx, dy;
             step_of(k, dx, dy);
             return (c == 0 ? dx : dy) / dt;
         }},
        {VtkArray::F64, "displacement", 3, [&](std::size_t r, int c) { const std::size_t k = std::size_t(order[r]); return c == 0 ? p.x[k] - origin(x0, k) : c == 1 ? p.y[k] - origin(y0, k) : 0.0; }},
        {VtkArray::I32, "id", 1, [&](std::size_t r, int) { const std::size_t k = std::size_t(order[r]); return double(p.id[k]); }},
    };
    const VtkArray coords = {VtkArray::F64, "Points", 3, [&](std::size_t r, int c) { const std::size_t k = std::size_t(order[r]); return c == 0 ? p.x[k] : c == 1 ? p.y[k] : 0.0; }};
    const VtkArray cells[] = {{VtkArray::I64, "connectivity", 1, [](std::size_t k, int) { return double(k); }},
                              {VtkArray::I64, "offsets", 1, [](std::size_t k, int) { return double(k + 1); }},
                              {VtkArray::U8, "types", 1, [](std::size_t, int) { return 1.0; }}};  // VTK_VERTEX
    detail::VtkXml x(f, binary);
    x.open("UnstructuredGrid");
    x.text("  <UnstructuredGrid>\n");
    x.time(sim.time(), sim.step_count());
    x.text(fmt::format("    <Piece NumberOfPoints=\"{0}\" NumberOfCells=\"{0}\">\n      <PointData Scalars=\"ep\" Vectors=\"velocity\" Tensors=\"stress\">\n", n));
    // WATER: the stress above is effective; the total is stress - pore_pressure I. (Named
    // here: BINARY writes the arrays' bytes in finish(), which reads them then.)
    const VtkArray pore = {VtkArray::F64, "pore_pressure", 1, [&](std::size_t r, int) { return p.pw[std::size_t(order[r])]; }};
    for (const VtkArray& a : point_data) x.array(a, n, "        ");
    if (sim.water()) x.array(pore, n, "        ");
    x.text("      </PointData>\n      <Points>\n");
    x.array(coords, n, "        ");
    x.text("      </Points>\n      <Cells>\n");
    for (const VtkArray& a : cells) x.array(a, n, "        ");
    x.text("      </Cells>\n    </Piece>\n  </UnstructuredGrid>\n");
    x.finish();
}

// One frame of the lattice as a VTK XML ImageData (its nodes the image's points, node
// (i, j) at (i L, j L)), with PointData mass (eq. 10, kg/m), velocity (the nodal
// increment over dt: at t + dt/2, m/s) and force (the net nodal force of the last step,
// gravity included, N/m). binary as for write_vtu.
LPFDM_DEF void write_vti(std::FILE* f, const Simulation& sim, bool binary) {
    using detail::VtkArray;
    const std::size_t n = sim.node_mass().size();
    const double dt = sim.scene().dt_s;
    const VtkArray node_data[] = {
        {VtkArray::F64, "mass", 1, [&](std::size_t k, int) { return sim.node_mass()[k]; }},
        {VtkArray::F64, "velocity", 3, [&](std::size_t k, int c) { return c == 0 ? sim.du_x()[k] / dt : c == 1 ? sim.du_y()[k] / dt : 0.0; }},
        {VtkArray::F64, "force", 3, [&](std::size_t k, int c) { return c == 0 ? sim.force_x()[k] : c == 1 ? sim.force_y()[k] : 0.0; }},
    };
    detail::VtkXml x(f, binary);
    x.open("ImageData");
    x.text(fmt::format("  <ImageData WholeExtent=\"0 {0} 0 {1} 0 0\" Origin=\"0 0 0\" Spacing=\"{2:.17g} {2:.17g} {2:.17g}\">\n", sim.mx(), sim.my(), sim.cell_size()));
    x.time(sim.time(), sim.step_count());
    x.text(fmt::format("    <Piece Extent=\"0 {} 0 {} 0 0\">\n      <PointData Scalars=\"mass\" Vectors=\"velocity\">\n", sim.mx(), sim.my()));
    for (const VtkArray& a : node_data) x.array(a, n, "        ");
    x.text("      </PointData>\n      <CellData>\n      </CellData>\n    </Piece>\n  </ImageData>\n");
    x.finish();
}

// The file of frame `step` of VTU series `name`: name_<step>.vtu, the step in at least
// six digits, so that the files sort in step order; with nodes, the lattice's frame
// name_nodes_<step>.vti.
LPFDM_DEF std::string vtu_frame_file(const std::string& name, long step, bool nodes) {
    if (nodes) return fmt::format("{}_nodes_{:06d}.vti", name, step);
    return fmt::format("{}_{:06d}.vtu", name, step);
}

// A ParaView collection of the frames (file, time) written: it opens the series at once.
LPFDM_DEF void write_pvd(std::FILE* f, const std::vector<std::pair<std::string, double>>& frames) {
    fmt::print(f, "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\">\n  <Collection>\n");
    for (const auto& fr : frames) fmt::print(f, "    <DataSet timestep=\"{:.15g}\" part=\"0\" file=\"{}\"/>\n", fr.second, fr.first);
    fmt::print(f, "  </Collection>\n</VTKFile>\n");
}

// Restart files (OUTPUT STATE, lpfdm --restart): everything the next step reads from the
// steps before it, in a versioned binary with a checksum, the same bytes whichever kernel
// and threads wrote it. Layout, in the machine's byte order:
//   "lpfdm state\n"  u32 version  u32 0x01020304 (byte order)  u64 file size  u64 digest,
//   items: u8 name length, name, u8 bytes per value, u64 values, the values' bytes
//          (Simulation::each_state in order, then "point_count" and every array of
//          Points::each_array that is a point's state, as "point_<name>"),
//   u64 checksum: FNV-1a of every byte before it.
// The digest is state_digest's of the deck text and of the options that change the
// scene: a state continues only the run it came from.
inline constexpr char kStateMagic[] = "lpfdm state\n";
inline constexpr std::uint32_t kStateVersion = 5;  // 2: ADVECT FLIP's point_flip_ux, point_flip_uy; 3: parked; 4: ADVECT FLIP's energy_d_slip; 5: SHIFT's energy_w_shift
namespace detail {
inline std::uint64_t fnv1a(const void* data, std::size_t n, std::uint64_t h = 14695981039346656037ull) {
    const unsigned char* c = static_cast<const unsigned char*>(data);
    for (std::size_t i = 0; i < n; ++i) { h ^= c[i]; h *= 1099511628211ull; }
    return h;
}
template <class T> struct IsVector : std::false_type {};
template <class T, class A> struct IsVector<std::vector<T, A>> : std::true_type {};
// The bytes, bytes per value and values of a state item (a number or a vector of them).
template <class M> void item_span(M& m, void*& data, std::size_t& size, std::size_t& count) {
    if constexpr (IsVector<std::remove_const_t<M>>::value) {
        static_assert(std::is_trivially_copyable_v<typename std::remove_const_t<M>::value_type>, "state items are plain values");
        data = const_cast<void*>(static_cast<const void*>(m.data())); size = sizeof(m[0]); count = m.size();
    } else {
        static_assert(std::is_trivially_copyable_v<std::remove_const_t<M>>, "state items are plain values");
        data = const_cast<void*>(static_cast<const void*>(&m)); size = sizeof(M); count = 1;
    }
}
}  // namespace detail
LPFDM_DEF std::uint64_t state_digest(const std::string& deck_text, const std::string& options) {
    return detail::fnv1a(options.data(), options.size(), detail::fnv1a(deck_text.data(), deck_text.size()));
}

// sim's state as a restart file. Returns whether every byte was written.
LPFDM_DEF bool write_state(std::FILE* f, const Simulation& sim, std::uint64_t digest) {
    std::string b(kStateMagic, sizeof kStateMagic - 1);
    auto raw = [&](const void* v, std::size_t bytes) { b.append(static_cast<const char*>(v), bytes); };
    const std::uint32_t version = kStateVersion, order = 0x01020304;
    const std::uint64_t size_slot = 0;
    raw(&version, 4); raw(&order, 4);
    const std::size_t size_at = b.size();
    raw(&size_slot, 8); raw(&digest, 8);
    auto item = [&](const char* name, const auto& m) {
        void* data; std::size_t size, count;
        detail::item_span(m, data, size, count);
        const std::uint8_t len = std::uint8_t(std::strlen(name)), sz = std::uint8_t(size);
        const std::uint64_t cnt = count;
        raw(&len, 1); raw(name, len); raw(&sz, 1); raw(&cnt, 8); raw(data, size * count);
    };
    sim.each_state(item);
    const Points& p = sim.points();
    const std::uint64_t n = p.size();
    item("point_count", n);
    p.each_array([&](const char* name, const auto& v, Points::Use, bool state) { if (state) item(("point_" + std::string(name)).c_str(), v); });
    const std::uint64_t total = b.size() + 8;
    std::memcpy(&b[size_at], &total, 8);
    const std::uint64_t sum = detail::fnv1a(b.data(), b.size());
    raw(&sum, 8);
    return std::fwrite(b.data(), 1, b.size(), f) == b.size();
}

// Continues sim (made from the same deck and options, not yet stepped) from the restart
// file at path. A file that is not a state, of another version or byte order, truncated,
// corrupt (checksum), of another deck (digest) or that does not fit the scene is refused
// with one diagnostic, and sim is left as it was.
LPFDM_DEF Diagnostics read_state(const std::string& path, Simulation& sim, std::uint64_t digest) {
    auto error = [&](const std::string& m) { return one_error(path, 0, 0, m); };
    std::error_code ec;
    if (std::filesystem::is_directory(path, ec)) return error("cannot read the state file: it is a directory");
    std::ifstream in(path, std::ios::binary);
    if (!in) return error(std::string("cannot open the state file: ") + std::strerror(errno));
    std::ostringstream ss;
    ss << in.rdbuf();
    const std::string b = ss.str();
    const std::size_t magic = sizeof kStateMagic - 1, head = magic + 4 + 4 + 8 + 8;
    if (b.size() < magic || b.compare(0, magic, kStateMagic) != 0) return error("not an lpfdm state file (it does not begin with 'lpfdm state')");
    if (b.size() < head + 8) return error(fmt::format("the state file is truncated: {} bytes, not even its header", b.size()));
    auto get = [&](std::size_t at, auto& v) { std::memcpy(&v, b.data() + at, sizeof v); };
    std::uint32_t version = 0, order = 0;
    std::uint64_t total = 0, dig = 0, sum = 0;
    get(magic, version); get(magic + 4, order); get(magic + 8, total); get(magic + 16, dig);
    if (order != 0x01020304) return error("the state file was written on a machine of the other byte order");
    if (version != kStateVersion) return error(fmt::format("the state file has format version {}; this lpfdm {} reads version {}", version, kVersion, kStateVersion));
    if (b.size() < total) return error(fmt::format("the state file is truncated: {} of its {} bytes", b.size(), total));
    if (b.size() > total || total < head + 8) return error(fmt::format("the state file is corrupt: {} bytes, its header says {}", b.size(), total));
    get(total - 8, sum);
    if (detail::fnv1a(b.data(), total - 8) != sum) return error("the state file is corrupt: its checksum does not match its contents");
    if (dig != digest)
        return error(fmt::format("the state file was written by a run of another deck, or with other --refine, --seed or --set options (digest {:016x}, this run {:016x})", dig, digest));
    // Twice through the items: first every check, then (apply) the copy.
    Points& p = sim.points();
    const std::size_t made = p.size();  // the points at step 0: no more can be left
    std::size_t at = head, n = 0, x_at = 0, y_at = 0, cell_at = 0, group_at = 0, yielded_at = 0;  // 0: no yielded flags
    std::string problem;
    auto next = [&](const char* name, auto& m, std::size_t want, bool apply) {
        if (!problem.empty()) return;
        void* data; std::size_t size, count;
        detail::item_span(m, data, size, count);
        std::uint8_t len = 0, sz = 0;
        std::uint64_t cnt = 0;
        if (at + 1 > total - 8) { problem = fmt::format("it ends before '{}'", name); return; }
        get(at, len);
        if (at + 1 + len + 9 > total - 8) { problem = fmt::format("it ends before '{}'", name); return; }
        const std::string got = b.substr(at + 1, len);
        get(at + 1 + len, sz); get(at + 2 + len, cnt);
        at += 10 + len;
        if (got != name) { problem = fmt::format("it holds '{}' where '{}' belongs", got, name); return; }
        if (sz != size || cnt != want) { problem = fmt::format("'{}' holds {} values of {} bytes, this scene needs {} of {}", name, cnt, sz, want, size); return; }
        if (cnt * sz > total - 8 - at) { problem = fmt::format("it ends inside '{}'", name); return; }
        if (apply) {
            if constexpr (detail::IsVector<std::remove_reference_t<decltype(m)>>::value) m.resize(std::size_t(cnt));
            detail::item_span(m, data, size, count);
            if (cnt) std::memcpy(data, b.data() + at, std::size_t(cnt) * sz);
        }
        at += std::size_t(cnt) * sz;
    };
    for (const bool apply : {false, true}) {
        at = head;
        sim.each_state([&](const char* name, auto& m) {
            std::size_t size = 0, count = 0;
            void* data;
            detail::item_span(m, data, size, count);
            next(name, m, count, apply);
        });
        std::uint64_t count = 0;
        next("point_count", count, 1, false);
        if (problem.empty()) {
            get(at - 8, count);
            if (count > made) problem = fmt::format("it holds {} points, this scene makes {}", count, made);
            n = std::size_t(count);
        }
        p.each_array([&](const char* name, auto& v, Points::Use, bool state) {
            if (!state) return;
            const std::string item = "point_" + std::string(name);
            if (item == "point_x") x_at = at + 10 + item.size();
            if (item == "point_y") y_at = at + 10 + item.size();
            if (item == "point_cell") cell_at = at + 10 + item.size();
            if (item == "point_group") group_at = at + 10 + item.size();
            if (item == "point_yielded" && !v.empty()) yielded_at = at + 10 + item.size();
            next(item.c_str(), v, v.empty() ? 0 : n, apply);
        });
        if (problem.empty() && at != total - 8) problem = "it holds more than this scene's state";
        for (std::size_t k = 0; k < n && problem.empty() && !apply; ++k) {
            std::int32_t c;
            std::uint16_t g;
            get(cell_at + 4 * k, c); get(group_at + 2 * k, g);
            if (c < 0 || c >= sim.mx() * sim.my() || g >= sim.groups().size()) problem = "a point lies outside the lattice";
            // Every kernel takes a point's cell to be the one holding its x, y (as each step leaves it).
            double x, y;
            get(x_at + 8 * k, x); get(y_at + 8 * k, y);
            if (problem.empty() && sim.cell_holding(x, y) != c)
                problem = fmt::format("point {} of the file lies at x = {:.17g} m, y = {:.17g} m, not in its cell ({}, {})", k, x, y, c % sim.mx(), c / sim.mx());
            // A yielded flag is 0 or 1 (the kernels set it to 1, and the state holds what they set).
            if (problem.empty() && yielded_at && std::uint8_t(b[yielded_at + k]) > 1)
                problem = fmt::format("point {} of the file has yielded flag {}, not 0 or 1", k, unsigned(std::uint8_t(b[yielded_at + k])));
        }
        if (!problem.empty()) return error("the state file does not fit this scene: " + problem);
    }
    sim.resumed();
    return {};
}
#endif  // LPFDM_NO_IO
#endif  // LPFDM_IMPLEMENTATION: from the fast kernel's step to the state files
}  // namespace lpfdm

#if defined(__clang__)
#pragma float_control(pop)
#endif
#endif  // LPFDM_IMPLEMENTATION || LPFDM_INTERNALS
