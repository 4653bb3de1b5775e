// lpfdm — command-line program: reads a deck, runs the LPFDM cycle, writes point
// tables and histories for gnuplot. Usage: lpfdm [options] DECK (see --help).
// This unit holds the kernel's definitions (lpfdm.hpp, USE), unless LPFDM_KERNEL_APART is
// defined: then it is main alone, linked against an implementation unit built apart
// (make test's sanitizer program shares the unit tests', tests/kernel.cpp).
#ifndef LPFDM_KERNEL_APART
#define LPFDM_IMPLEMENTATION
#endif
#include "lpfdm.hpp"

#include <algorithm>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include <fmt/format.h>
#if defined(_OPENMP)
#include <omp.h>
#endif
#include <sys/resource.h>
#include <sys/stat.h>
#include <getopt.h>
#include <unistd.h>

namespace {

volatile std::sig_atomic_t g_interrupted = 0;
extern "C" void on_sigint(int) { g_interrupted = 1; }

constexpr int kExitBadInput = 2, kExitNumerical = 3, kExitInterrupted = 130;
// The energy the cycle may create, as a fraction of the energy in play, before the run is
// warned of it (see the run loop).
constexpr double kEnergyCreated = 0.1;
using lpfdm::kAtRest;  // at rest below it (lpfdm.hpp; Rest::said writes it)

// Whether the scene ended at rest: the unbalanced-force ratio read with the energy account
// (run_steps), the last reading and the first step of the last stretch of readings below
// kAtRest (-1: the last reading was above).
struct Rest {
    double ratio = -1;
    long since = -1;
    long every = 0;
    std::string said() const {
        if (ratio < 0) return "";
        if (since >= 0) return fmt::format("; at rest: unbalanced-force ratio {:.3g}, below 1e-3 since step {} (read every {} steps)", ratio, since, every);
        return fmt::format("; moving: unbalanced-force ratio {:.3g} at the end (at rest below 1e-3)", ratio);
    }
};

// The options: getopt_long's table, --help and decks/README.md (a test compares them) from
// this one list. Short forms: -n for --steps (-s would be any of --steps, --seed, --set,
// --strict), -D for --set (as a compiler's -D NAME=VALUE).
struct OptionSpec {
    const char* name;
    char brief;       // the short form, or 0
    const char* arg;  // the value's name, or nullptr for a flag
    const char* help; // lines after the first are indented under it
};
constexpr int kSeed = 256, kStrict = 257, kNoAvx2 = 258, kRestart = 259, kFos = 260, kFosTol = 261;  // getopt values of the options without a short form
const OptionSpec kOptions[] = {
    {"output", 'o', "DIR", "write the output files into DIR (created; default: the current directory)"},
    {"steps", 'n', "N", "run N steps instead of the deck's"},
    {"refine", 'r', "K", "K times finer lattice: same geometry in metres, dt / K, K times the steps"},
    {"seed", 0, "N", "seed of the strength scatter instead of the deck's SEED"},
    {"set", 'D', "K=V", "override one deck parameter, e.g. --set MATERIAL1.C=12000, --set CLUSTER1.PPC=4,\n"
                        "--set DAMPING.ALPHA=0 (the keys are listed below); may be given several times"},
    {"threads", 't', "N", "use N threads (default 1, or OMP_NUM_THREADS; the output is the same for any N)"},
    {"kernel", 'k', "K", "the code that runs the cycle (the same output with each):\n"
                         "fast       the default: threads, four values per AVX2 register where the processor has it\n"
                         "scalar     fast, one value at a time (no AVX2)\n"
                         "reference  the plain cycle, every cell, point and node, one thread: the definition"},
    {"restart", 0, "F", "continue the run saved in the state file F (OUTPUT STATE) from its step; the deck and the\n"
                        "options --refine, --seed and --set must be the run's own (--steps may run it further)"},
    {"strict", 0, nullptr, "warnings are errors: a deck that draws one stops with exit status 2"},
    {"fos", 0, nullptr, "the factor of safety by strength reduction instead of the run: trials of the deck's scene with\n"
                        "c / F and tan(phi) / F, F bracketed between one that stands and one that fails; the\n"
                        "deck's outputs of the last trial that stood go to DIR/stands, of the first that failed to\n"
                        "DIR/fails. Exit status 0 with a factor, 3 when the scene fails even at the smallest F"},
    {"fos-tol", 0, "D", "--fos brackets F to within D (default 0.01)"},
    {"profile", 'p', nullptr, "print the time of each phase of the cycle, peak memory and bytes per point"},
    {"no-avx2", 0, nullptr, "the same as --kernel scalar"},
    {"quiet", 'q', nullptr, "no progress line and no summary"},
    {"help", 'h', nullptr, "this text"},
    {"version", 'V', nullptr, "the version"},
};
int option_value(const OptionSpec& o) {
    if (o.brief) return o.brief;
    const std::string n = o.name;
    return n == "seed" ? kSeed : n == "strict" ? kStrict : n == "restart" ? kRestart : n == "fos" ? kFos : n == "fos-tol" ? kFosTol : kNoAvx2;
}

// The usage text: the synopsis, each option from kOptions, the exit status.
std::string usage_text() {
    std::string out = "usage: lpfdm [options] DECK\n"
                      "       lpfdm [options] --restart F DECK\n"
                      "       lpfdm [options] --fos DECK\n"
                      "Runs the Lagrangian Particle Finite Difference Method on the scene of DECK.\n"
                      "\n"
                      "options (a value may follow as the next word or after '=': --steps 100, --steps=100, -n 100):\n";
    for (const OptionSpec& o : kOptions) {
        std::string head = "  ";
        head += o.brief ? std::string("-") + o.brief + ", " : std::string("    ");
        head += std::string("--") + o.name + (o.arg ? std::string(" ") + o.arg : "");
        head.resize(std::max<std::size_t>(head.size() + 2, 22), ' ');
        const std::string indent(head.size(), ' ');
        std::string help = o.help;
        for (std::size_t nl; (nl = help.find('\n')) != std::string::npos;) {
            out += head + help.substr(0, nl) + "\n";
            help = help.substr(nl + 1);
            head = indent;
        }
        out += head + help + "\n";
    }
    out += "\nexit status: 0 done, 2 bad deck, options or state file, 3 numerical trouble (--fos: or the scene fails\n"
           "at the smallest trial factor), 130 interrupted\n"
           "(SIGINT: the step under way is finished, its frame, history row and state written)\n";
    return out;
}

struct Options {
    std::string deck, outdir = ".", restart;
    long refine = 1, steps = 0;
    long long seed = -1;
    bool quiet = false, profile = false, strict = false, fos = false;
    double fos_tol = 0.01;
    lpfdm::Kernel kernel = lpfdm::Kernel::Fast;
    long threads = 0;
    std::vector<std::pair<std::string, double>> settings;
    std::vector<std::string> setting_text;  // each --set as written
};

bool parse_long(const char* s, long long lo, long long hi, long long& v) {
    char* end = nullptr;
    errno = 0;
    v = std::strtoll(s, &end, 10);
    return errno == 0 && end != s && *end == '\0' && v >= lo && v <= hi;
}


// An output file written as NAME.part and renamed when complete, so a stopped run
// never leaves a table that looks complete.
struct OutFile {
    std::string final_path, part_path;
    std::FILE* f = nullptr;
    const lpfdm::Output* spec = nullptr;
    bool first_frame = true;
    std::vector<std::pair<std::string, double>> frames, node_frames;  // VTU: the frames written (file, time)
};

bool make_dir(const std::string& d) {
    if (d.empty()) return false;
    std::string cur;
    for (std::size_t i = 0; i <= d.size(); ++i) {
        if (i == d.size() || d[i] == '/') {
            if (!cur.empty() && mkdir(cur.c_str(), 0777) != 0 && errno != EEXIST) return false;
        }
        if (i < d.size()) cur += d[i];
    }
    struct stat st;
    return stat(d.c_str(), &st) == 0 && S_ISDIR(st.st_mode);
}

double physical_memory_bytes() {
    const long pages = sysconf(_SC_PHYS_PAGES), size = sysconf(_SC_PAGE_SIZE);
    return pages > 0 && size > 0 ? double(pages) * double(size) : 0.0;
}


// Option c (getopt_long's value) with its value arg, when it is one that sets opt (or
// records its mistake in errors): true; false for the others (help, version, mistakes).
bool take_option(int c, const char* arg, Options& opt, std::vector<std::string>& cli_errors) {
    long long v = 0;
    switch (c) {
    case 'q': opt.quiet = true; break;
    case 'p': opt.profile = true; break;
    case kStrict: opt.strict = true; break;
    case kNoAvx2: opt.kernel = lpfdm::Kernel::Scalar; break;
    case kFos: opt.fos = true; break;
    case kFosTol: {
        double x = 0;
        if (!lpfdm::read_number(arg, x) || !(x >= 1e-4 && x <= 1)) cli_errors.push_back(std::string("--fos-tol needs a number from 1e-4 to 1, not '") + arg + "'");
        else opt.fos_tol = x;
        break;
    }
    case 'o':
        if (!*arg) cli_errors.push_back("-o needs a directory");
        else opt.outdir = arg;
        break;
    case 'r':
        if (!parse_long(arg, 1, 64, v)) cli_errors.push_back(std::string("--refine needs a whole number from 1 to 64, not '") + arg + "'");
        else opt.refine = long(v);
        break;
    case 'n':
        if (!parse_long(arg, 1, 1'000'000'000LL, v)) cli_errors.push_back(std::string("--steps needs a whole number from 1 to 1e9, not '") + arg + "'");
        else opt.steps = long(v);
        break;
    case kSeed:
        if (!parse_long(arg, 0, 9'007'199'254'740'992LL, v)) cli_errors.push_back(std::string("--seed needs a whole number >= 0, not '") + arg + "'");
        else opt.seed = v;
        break;
    case 't':
        if (!parse_long(arg, 1, 1024, v)) cli_errors.push_back(std::string("--threads needs a whole number from 1 to 1024, not '") + arg + "'");
        else opt.threads = long(v);
        break;
    case 'k': {
        const std::string d = arg;
        if (d == "fast") opt.kernel = lpfdm::Kernel::Fast;
        else if (d == "scalar") opt.kernel = lpfdm::Kernel::Scalar;
        else if (d == "reference") opt.kernel = lpfdm::Kernel::Reference;
        else cli_errors.push_back("--kernel needs fast, scalar or reference, not '" + d + "'" + lpfdm::did_you_mean(d, {"fast", "scalar", "reference"}));
        break;
    }
    case kRestart:
        if (!*arg) cli_errors.push_back("--restart needs a state file");
        else opt.restart = arg;
        break;
    case 'D': {
        const std::string kv = arg;
        const std::size_t eq = kv.find('=');
        double x = 0;
        if (eq == std::string::npos || !lpfdm::read_number(kv.substr(eq + 1), x)) {
            cli_errors.push_back("--set needs CARD.PARAM=VALUE with a finite number, e.g. --set MATERIAL1.C=12000, not '" + kv + "'");
        } else {
            opt.settings.push_back({kv.substr(0, eq), x});
            opt.setting_text.push_back(kv);
        }
        break;
    }
    default: return false;
    }
    return true;
}

// The command line into opt, every mistake collected in cli_errors (reported with the
// deck's): -1 to go on, or the exit status of a run that ends here (--help, --version).
int read_command_line(int argc, char** argv, Options& opt, std::vector<std::string>& cli_errors) {
    std::vector<std::string> decks;
    std::vector<option> longs;
    std::string shorts = ":";  // ':' first: a missing value is told from an unknown option
    std::vector<std::string> names;
    for (const OptionSpec& o : kOptions) {
        longs.push_back({o.name, o.arg ? required_argument : no_argument, nullptr, option_value(o)});
        if (o.brief) shorts += std::string(1, o.brief) + (o.arg ? ":" : "");
        names.push_back(std::string("--") + o.name);
        if (o.brief) names.push_back(std::string("-") + o.brief);
    }
    longs.push_back({nullptr, 0, nullptr, 0});
    auto spelled = [&](int c) {  // how option c is named in a message
        for (const OptionSpec& o : kOptions)
            if (option_value(o) == c) return std::string("--") + o.name;
        return std::string("-") + char(c);
    };
    auto takes_value = [&](const std::string& name) {  // whether option --name or -x takes a value
        for (const OptionSpec& o : kOptions)
            if (name == std::string("--") + o.name || (o.brief && name == std::string("-") + o.brief)) return o.arg != nullptr;
        return false;
    };
    // A long option is written in full: getopt_long would take any unambiguous beginning
    // (--thread for --threads), silently, and a beginning that names one option today may
    // name two once another is added. A beginning, or a misspelling, is refused with the
    // option meant.
    auto unknown_option = [&](const std::string& bare) {
        const std::string near = lpfdm::nearest_name(bare, names);
        bool beginning = false;
        for (const OptionSpec& o : kOptions) {
            const std::string full = std::string("--") + o.name;
            beginning |= bare.size() > 2 && full.size() > bare.size() && full.compare(0, bare.size(), bare) == 0;
        }
        if (bare == "--no-avx512")  // retired: the consult runs four points per AVX2 register everywhere
            return std::string("--no-avx512 is retired: the Mohr-Coulomb consult takes four points per AVX2 register on every processor (the same output as before); leave the option out");
        const std::string note = beginning ? "options are written in full" : "";
        if (near.empty()) return "unknown option '" + bare + "'" + (note.empty() ? "" : " (" + note + ")");
        return "unknown option '" + bare + "' (did you mean " + near + "?" + (note.empty() ? "" : " " + note) + ")";
    };
    auto option_name = [](const char* word) {  // "--name" of "--name=value"
        const std::string w = word;
        return w.substr(0, w.find('='));
    };
    // The word after an unknown option, when it may be the option's value (the option it is
    // nearest to takes one, or it is near none): not the deck, when a deck is named too.
    std::vector<const char*> maybe_values;
    opterr = 0;
    for (;;) {
        int li = -1;
        const int c = getopt_long(argc, argv, shorts.c_str(), longs.data(), &li);
        if (c == -1) break;
        if (li >= 0) {  // a long option (getopt_long set li): as typed, up to '='
            const bool apart = optarg && optind >= 2 && optarg == argv[optind - 1];  // its value the next word
            const std::string as = option_name(argv[optind - (apart ? 2 : 1)]);
            if (as != std::string("--") + longs[std::size_t(li)].name) {
                cli_errors.push_back(unknown_option(as));  // (its value, if any, read and set aside)
                continue;
            }
        }
        if (take_option(c, optarg, opt, cli_errors)) continue;
        switch (c) {
        case 'h': std::fputs(usage_text().c_str(), stdout); std::fputs(("\n" + lpfdm::deck_help()).c_str(), stdout); return 0;
        case 'V': std::printf("lpfdm %s\n", lpfdm::kVersion); return 0;
        case ':': {  // (argv[optind - 1]: the option, the last word)
            const std::string word = optind > 0 && optind <= argc ? argv[optind - 1] : "";
            if (word.rfind("--", 0) == 0 && option_name(word.c_str()) != spelled(optopt)) cli_errors.push_back(unknown_option(option_name(word.c_str())));
            else cli_errors.push_back(spelled(optopt) + " needs a value");
            break;
        }
        default: {  // '?': an unknown, ambiguous or misspelt option, or a flag given a value
            const std::string word = optind > 0 && optind <= argc ? argv[optind - 1] : "";
            if (word.rfind("--", 0) == 0) {
                const std::string bare = option_name(word.c_str());
                if (word.find('=') != std::string::npos && optopt && bare == spelled(optopt)) {
                    cli_errors.push_back(bare + " takes no value");
                } else {
                    cli_errors.push_back(unknown_option(bare));
                    const std::string near = lpfdm::nearest_name(bare, names);
                    if (word.find('=') == std::string::npos && optind < argc && argv[optind][0] != '-' && (near.empty() || takes_value(near)))
                        maybe_values.push_back(argv[optind]);
                }
            } else {
                cli_errors.push_back(std::string("unknown option '-") + char(optopt) + "'" + lpfdm::did_you_mean(std::string("-") + char(optopt), names));
            }
        }
        }
    }
    // The words left are the deck, but for the values of unknown options (--stesp 10 DECK):
    // those are set aside when a deck is named too, or when they name no file (--stesp 10).
    std::vector<const char*> words(argv + optind, argv + argc);
    auto is_value = [&](const char* w) {
        struct stat st;
        return std::find(maybe_values.begin(), maybe_values.end(), w) != maybe_values.end() && (words.size() > 1 || stat(w, &st) != 0);
    };
    for (const char* w : words)
        if (!is_value(w)) decks.push_back(w);
    if (decks.size() > 1) cli_errors.push_back("one deck, please: " + std::to_string(decks.size()) + " are named");
    if (decks.empty()) cli_errors.push_back("no deck given");
    if (decks.size() == 1) opt.deck = decks[0];
    return -1;
}

// The deck (its text into text, the scene into scene) and the options read and checked in
// one pass: every error and warning, in the deck's order (a mistake of an option that
// needs the deck, such as --set, into cli_errors).
lpfdm::Diagnostics read_and_check(const Options& opt, std::vector<std::string>& cli_errors, lpfdm::Scene& scene, std::string& text) {
    lpfdm::Diagnostics diags;
    lpfdm::Unread unread;
    if (!opt.deck.empty()) {
        diags = lpfdm::load_file(opt.deck, text);
        if (diags.empty()) diags = lpfdm::parse_deck_text(text, opt.deck, scene, &unread);
        else unread.all();
        // (a file that is no deck, or no text, sets nothing: its --set would only echo that)
        const bool loaded = !(unread.grid && unread.step && unread.materials && unread.clusters);
        // A key of a card the reader could not read (CLUSTER1.PPC of a deck whose CLUSTER is
        // misspelt) is the card's error, reported at the card, not a second one here.
        auto unread_card = [&](const std::string& key) {
            auto is = [&](const char* card) { return key.compare(0, std::strlen(card), card) == 0; };
            return (is("CLUSTER") && unread.clusters) || (is("MATERIAL") && unread.materials) || (is("FIX") && unread.fixes);
        };
        for (const auto& kv : opt.settings) {
            const std::string e = loaded ? lpfdm::apply_setting(scene, kv.first, kv.second) : "";
            if (!e.empty() && !(e.compare(0, 12, "there is no ") == 0 && unread_card(kv.first))) cli_errors.push_back("--set " + kv.first + ": " + e);
        }
        if (opt.refine > 1) {
            if (long(scene.mx) * opt.refine > 1'000'000 || long(scene.my) * opt.refine > 1'000'000)
                cli_errors.push_back("--refine " + std::to_string(opt.refine) + " makes the lattice larger than 1e6 cells a side");
            else
                lpfdm::refine(scene, int(opt.refine));
        }
        if (opt.steps > 0) scene.steps = opt.steps;
        if (opt.seed >= 0) scene.seed = std::uint64_t(opt.seed);
        const lpfdm::Diagnostics v = lpfdm::validate(scene, unread);
        diags.insert(diags.end(), v.begin(), v.end());
        if (v.empty() && !unread.grid && scene.mx > 0 && scene.my > 0 && scene.cell_m > 0) {  // (a scene validate refused may not be counted)
            const double points = lpfdm::count_points(scene);
            const double need = lpfdm::estimate_bytes(scene, points), have = physical_memory_bytes();
            if (have > 0 && need > 0.8 * have)
                diags.push_back({scene.grid_pos, fmt::format("the scene needs about {:.3g} GiB ({:.0f} points on {} x {} cells); this machine has {:.3g} GiB",
                                                             need / 1073741824.0, points, scene.mx, scene.my, have / 1073741824.0)});
        }
        lpfdm::Diagnostics w = lpfdm::warnings(scene, unread);
        for (auto& d : w) d.warning = !opt.strict;
        diags.insert(diags.end(), w.begin(), w.end());
        lpfdm::sort_diagnostics(diags);
    }
    return diags;
}

// What a state file must have been written by: the deck and the options that change the
// scene (not --steps: a restart may run further).
std::uint64_t scene_digest(const Options& opt, const lpfdm::Scene& scene, const std::string& text) {
    // What a state file must have been written by: the deck and the options that change
    // the scene (not --steps: a restart may run further).
    std::string scene_options = fmt::format("refine {} seed {}", opt.refine, opt.seed);
    for (const auto& kv : opt.settings) scene_options += fmt::format(" set {}={:.17g}", kv.first, kv.second);
    for (const auto& k : scene.shakes) {  // the records (a motion file edited between the runs is another scene)
        std::string bytes(reinterpret_cast<const char*>(k.t.data()), k.t.size() * sizeof(double));  // the times' bytes, then the values'
        bytes.append(reinterpret_cast<const char*>(k.a.data()), k.a.size() * sizeof(double));
        const std::uint64_t h = lpfdm::fnv1a64(bytes);
        scene_options += fmt::format(" motion {:016x}", h);
    }
    return lpfdm::state_digest(text, scene_options);
}

// The run's output files (its OUTPUT cards): tables and histories written as NAME.part and
// renamed when complete, so a stopped run never leaves a table that looks complete; VTU
// frames, collections and states written whole the same way.
struct Outputs {
    const Options& opt;
    lpfdm::Simulation& sim;
    const lpfdm::RunInfo& run;
    std::uint64_t digest;
    std::vector<OutFile> outs;
    bool write_failed = false;

    // Each file opened (NAME.part) with its header and first frame; false when one cannot be.
    bool open() {
        for (const auto& o : sim.scene().outputs) {
            OutFile of;
            of.final_path = opt.outdir + "/" + o.file;
            of.part_path = of.final_path + ".part";
            of.spec = &o;
            if (o.kind == lpfdm::Output::Vtu || o.kind == lpfdm::Output::State) {  // files written whole
                outs.push_back(of);
                continue;
            }
            of.f = std::fopen(of.part_path.c_str(), "wb");
            if (!of.f) {
                std::fprintf(stderr, "%s:%d:%d: error: cannot write '%s': %s\n", o.pos.file.c_str(), o.pos.line, o.pos.col, of.part_path.c_str(), std::strerror(errno));
                for (auto& p : outs) if (p.f) { std::fclose(p.f); std::remove(p.part_path.c_str()); }
                return false;
            }
            if (o.kind == lpfdm::Output::Points) {
                lpfdm::write_points_header(of.f, sim, opt.deck, &run);
                lpfdm::write_points_frame(of.f, sim, true);
                of.first_frame = false;
            } else {
                lpfdm::write_history_header(of.f, sim, opt.deck, &run);
            }
            outs.push_back(of);
        }
        for (auto& o : outs)
            if (o.spec->kind == lpfdm::Output::Vtu) vtu_frame(o);
        return true;
    }

    // A file written whole as NAME.part, then renamed (VTU frames and collections, states).
    template <class W> bool write_whole(const std::string& path, const W& write) {
        const std::string part = path + ".part";
        std::FILE* f = std::fopen(part.c_str(), "wb");
        bool ok = f && write(f);
        if (f) ok &= std::fclose(f) == 0;
        ok = ok && std::rename(part.c_str(), path.c_str()) == 0;
        if (!ok) std::fprintf(stderr, "lpfdm: error: cannot write '%s': %s\n", path.c_str(), std::strerror(errno));
        return ok;
    }
    // A frame of a VTU series, and its collection written anew.
    void vtu_frame(OutFile& o) {
        const std::string file = lpfdm::vtu_frame_file(o.spec->file, sim.step_count());
        write_failed |= !write_whole(opt.outdir + "/" + file, [&](std::FILE* f) {
            lpfdm::write_vtu(f, sim, sim.initial_x(), sim.initial_y(), o.spec->binary);  // displacement from step 0, by id
            return !std::ferror(f);
        });
        o.frames.push_back({file, sim.time()});
        write_failed |= !write_whole(opt.outdir + "/" + o.spec->file + ".pvd", [&](std::FILE* f) {
            lpfdm::write_pvd(f, o.frames);
            return !std::ferror(f);
        });
        if (!o.spec->nodes) return;
        const std::string nodes = lpfdm::vtu_frame_file(o.spec->file, sim.step_count(), true);
        write_failed |= !write_whole(opt.outdir + "/" + nodes, [&](std::FILE* f) {
            lpfdm::write_vti(f, sim, o.spec->binary);
            return !std::ferror(f);
        });
        o.node_frames.push_back({nodes, sim.time()});
        write_failed |= !write_whole(opt.outdir + "/" + o.spec->file + "_nodes.pvd", [&](std::FILE* f) {
            lpfdm::write_pvd(f, o.node_frames);
            return !std::ferror(f);
        });
    }
    void save_state(OutFile& o) {
        write_failed |= !write_whole(o.final_path, [&](std::FILE* f) { return lpfdm::write_state(f, sim, digest); });
    }
    bool finish(const std::string& note) {
        bool ok = !write_failed;
        for (auto& o : outs) {
            if (!o.f) continue;
            if (!note.empty()) std::fprintf(o.f, "# %s\n", note.c_str());
            ok &= std::fclose(o.f) == 0;
            ok &= std::rename(o.part_path.c_str(), o.final_path.c_str()) == 0;
        }
        if (!ok) std::fprintf(stderr, "lpfdm: error: writing the output files failed\n");
        return ok;
    }
};

// A run gone wrong at step n (Simulation::healthy): where, on stderr; the last good frame
// and history row written where the points are still finite. Returns the note for the files.
std::string report_trouble(const lpfdm::Simulation& sim, long n, Outputs& out) {
    const long k = sim.first_nonfinite_point();
    const auto& p = sim.points();
    std::string where;
    if (k >= 0) {
        where = fmt::format("; first bad point: id {} in cell ({}, {})", p.id[std::size_t(k)], p.cell[std::size_t(k)] % sim.mx(), p.cell[std::size_t(k)] / sim.mx());
    } else {
        int ni = 0, nj = 0;
        long q = -1;
        sim.worst_node(ni, nj, q);
        where = fmt::format("; worst node ({}, {}) at x = {:.6g} m, y = {:.6g} m", ni, nj, ni * sim.cell_size(), nj * sim.cell_size());
        if (q >= 0) where += fmt::format(", next to point id {} in cell ({}, {})", p.id[std::size_t(q)], p.cell[std::size_t(q)] % sim.mx(), p.cell[std::size_t(q)] / sim.mx());
    }
    const std::string why = std::isfinite(sim.kinetic_energy())
        ? fmt::format("a node moved {:.3g} m in one step, more than half a cell: the run is unstable", sim.max_du())
        : "a non-finite value appeared";
    std::fprintf(stderr, "lpfdm: error: numerical trouble at step %ld (t = %.6g s): %s%s\n", n, sim.time(), why.c_str(), where.c_str());
    // The points are still finite when the trouble is in the nodal increments: their
    // state at this step is the last good one, so it is written as the last frame
    // (not to a VTU series, whose velocities come from the nodes, nor a state).
    if (k < 0)
        for (auto& o : out.outs) {
            if (o.spec->kind == lpfdm::Output::Points) lpfdm::write_points_frame(o.f, sim, false);
            else if (o.spec->kind == lpfdm::Output::History && std::isfinite(sim.kinetic_energy())) lpfdm::write_history_row(o.f, sim);
        }
    return fmt::format("run stopped at step {}: numerical trouble; the frames above are the last good ones", n);
}

// The steps of the run, each output written when due, until the last step, numerical
// trouble or SIGINT: the exit status; the particle-steps and wall time, for the summary.
int run_steps(lpfdm::Simulation& sim, const Options& opt, Outputs& out, double& particle_steps, double& wall, Rest& rest) {
    std::signal(SIGINT, on_sigint);
    const long steps = sim.scene().steps, first = sim.step_count() + 1;
    const bool progress = !opt.quiet && isatty(2);
    const auto t0 = std::chrono::steady_clock::now();
    auto last_print = t0;
    int status = 0;
    std::string note;
    // Whether output o is due at step n: a history row every n steps (every step without
    // EVERY; the last only when EVERY is above the steps, a warning); a frame or a state every n steps and at the last step (without EVERY only
    // there; frames also at the first).
    auto due = [&](const OutFile& o, long n) {
        const long every = o.spec->every;
        if (o.spec->kind == lpfdm::Output::History) return n % (every > 0 ? every : 1) == 0 || (every > steps && n == steps);  // (warned)
        return (every > 0 && n % every == 0) || n == steps;
    };
    // Energy the cycle creates (energy_error < 0) is trouble the checks above do not stop.
    // The account is read every steps / 200 steps of the run, at least 100 apart (a reading
    // is a pass over the points, about half a step: read every other step, it slowed the
    // 400-step benchmark by 35 %), counted from step 0 so that a run continued with the
    // same --steps reads it at the same steps; also at the last step and at an interrupted
    // one. Reading it changes no result. A creation of more than kEnergyCreated of the
    // energy in play is reported at the end, on stderr only: a run continued with
    // --restart must write the whole run's tables, and it has not seen the steps before.
    // The shipped decks create at most 6.3 % (freefall.deck's impact on a block 4 cells
    // across, for one step; 5.6 % over the impact; 2.7 % and 1.0 % at 8 and 16 cells
    // across: a first-order error in L), so the warning marks a creation 1.6 times the
    // coarsest shipped impact's: a body too coarsely resolved for what it does, or a cycle
    // gone wrong.
    const long energy_every = std::max(100L, steps / 200);
    double created = 0;  // the lowest energy_error read, and its step
    long created_step = 0;
    for (long n = first; n <= steps; ++n) {
        particle_steps += double(sim.points().size());
        sim.step();
        if (sim.healthy() && (n % energy_every == 0 || n == steps || g_interrupted)) {
            const double e = sim.energy().error;
            if (e < created) { created = e; created_step = n; }
            rest.ratio = sim.unbalanced_ratio();
            rest.every = energy_every;
            if (!(rest.ratio < kAtRest)) rest.since = -1;
            else if (rest.since < 0) rest.since = n;
        }
        if (!sim.healthy()) {
            note = report_trouble(sim, n, out);
            status = kExitNumerical;
            break;
        }
        // Each output due at this step, and on SIGINT every output not due (the
        // interrupted step once).
        const bool stop = g_interrupted;
        for (auto& o : out.outs) {
            if (!due(o, n) && !stop) continue;
            switch (o.spec->kind) {
            case lpfdm::Output::History: lpfdm::write_history_row(o.f, sim); break;
            case lpfdm::Output::Points: lpfdm::write_points_frame(o.f, sim, o.first_frame); o.first_frame = false; break;
            case lpfdm::Output::Vtu: out.vtu_frame(o); break;
            case lpfdm::Output::State: out.save_state(o); break;
            }
        }
        if (stop) {
            note = fmt::format("run interrupted at step {} of {}", n, steps);
            bool saved = false;
            for (const auto& o : out.outs) saved |= o.spec->kind == lpfdm::Output::State;
            std::fprintf(stderr, "\nlpfdm: interrupted at step %ld of %ld; the last frame and a history row were written%s\n", n, steps,
                         saved ? ", and the state (--restart continues it)" : "");
            status = kExitInterrupted;
            break;
        }
        if (progress) {
            const auto now = std::chrono::steady_clock::now();
            if (std::chrono::duration<double>(now - last_print).count() > 0.5 || n == steps) {
                last_print = now;
                const double el = std::chrono::duration<double>(now - t0).count();
                std::fprintf(stderr, "\rstep %ld/%ld (%3.0f%%)  ke %.4g J/m  %.0f s left   ", n, steps, 100.0 * n / steps, sim.kinetic_energy(),
                             el / double(n - first + 1) * double(steps - n));
            }
        }
    }
    if (progress) std::fputc('\n', stderr);
    if (status != kExitNumerical && created < -kEnergyCreated) {
        const std::string w = fmt::format(
            "warning: the cycle created energy: energy_error reached {:.3g} at step {} (t = {:.6g} s; read every {} steps), "
            "{:.1f} % of the energy in play; such creation falls with the cell size (decks/freefall.deck's impact: 5.6, 2.7 "
            "and 1.0 % with 4, 8 and 16 cells across the block): refine the lattice (--refine 2) and compare",
            created, created_step, double(created_step) * sim.scene().dt_s, energy_every, -100 * created);
        std::fprintf(stderr, "lpfdm: %s\n", w.c_str());
    }
    wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (!out.finish(note) && status == 0) status = kExitBadInput;
    return status;
}

// The kernel that ran, as the summary line says it: the provenance lines' name, why the
// points go one at a time where the processor has AVX2, and why the point pass takes one
// thread (Simulation::modes).
std::string kernel_said(const lpfdm::Simulation& sim, const lpfdm::RunInfo& run) {
    const lpfdm::Modes& m = sim.modes();
    std::string s = run.kernel;
    if (sim.wide() && *m.points_why) s += std::string(", points one at a time (") + m.points_why + ")";
    if (sim.threads() > 1 && *m.threads_why) s += std::string(", the point pass on one thread (") + m.threads_why + ")";
    return s;
}

// --profile: the time of each phase, peak memory, bytes per point, and which loops ran.
void print_profile(const lpfdm::Simulation& sim, int nthreads) {
    struct rusage ru;
    getrusage(RUSAGE_SELF, &ru);
    double total = 0;
    for (int k = 0; k < lpfdm::Simulation::kPhases; ++k) total += sim.phase_seconds()[k];
    const bool ref = sim.kernel() == lpfdm::Kernel::Reference;
    const std::string options = std::string("cells and nodes four per AVX2 register, points one at a time (") + sim.modes().points_why + ")";
    const char* lanes = ref ? "the reference cycle"
                        : !sim.wide() ? "points, cells and nodes one at a time"
                        : !*sim.modes().points_why ? "points, cells and nodes four per AVX2 register"
                        : options.c_str();
    std::printf("profile: threads %d, peak memory %.1f MiB, %.1f bytes per point in the point arrays, %s\n", ref ? 1 : nthreads,
                double(ru.ru_maxrss) / 1024.0, sim.bytes_per_point(), lanes);
    for (int k = 0; k < lpfdm::Simulation::kPhases; ++k)
        std::printf("profile: %-15s %8.3f s  %5.1f %%\n", lpfdm::Simulation::phase_name(k), sim.phase_seconds()[k],
                    total > 0 ? 100 * sim.phase_seconds()[k] / total : 0.0);
    if (sim.return_updates() > 0)  // inside the points phase (thread seconds)
        std::printf("profile:   of which the Mohr-Coulomb consult (elastic test and return) %.3f s, %.1f ns per point-update (%ld)\n", sim.return_seconds(),
                    1e9 * sim.return_seconds() / double(sim.return_updates()), sim.return_updates());
}


// How the run was made, for the provenance lines of its files (lpfdm::write_provenance).
lpfdm::RunInfo run_info(const lpfdm::Simulation& sim, const Options& opt, const std::string& text, int nthreads) {
    lpfdm::RunInfo run;
    run.deck = opt.deck;
    run.deck_digest = lpfdm::fnv1a64(text);
    run.settings = opt.setting_text;
    run.steps = opt.steps;
    run.refine = opt.refine;
    run.seed = opt.seed;
    run.threads = sim.kernel() == lpfdm::Kernel::Reference ? 1 : nthreads;
    run.kernel = sim.kernel() == lpfdm::Kernel::Reference ? "reference" : sim.wide() ? "fast (AVX2)" : opt.kernel == lpfdm::Kernel::Fast ? "fast (no AVX2 here)" : "scalar";
    return run;
}

// --fos: what keeps the deck's scene from having a factor of safety (a scene that cannot
// come to rest, or has no strength to reduce), at the cards concerned; and, as warnings,
// where its factor is not verified (lpfdm::fos_warnings).
lpfdm::Diagnostics fos_problems(const lpfdm::Scene& scene) {
    lpfdm::Diagnostics d;
    bool mohr = false;
    for (const auto& m : scene.materials) mohr |= m.model == lpfdm::Model::MohrCoulomb;
    if (!mohr) d.push_back({scene.grid_pos, "--fos reduces the strength of MOHR materials, and the deck has none"});
    for (const auto& k : scene.shakes)
        d.push_back({k.pos, "--fos finds the factor of safety of a scene at rest under GRAVITY, and SHAKE moves the ground (a seismic coefficient is a horizontal GRAVITY gx)"});
    for (const auto& w : scene.walls)
        if (w.vx != 0 || w.vy != 0) d.push_back({w.pos, fmt::format("--fos finds the factor of safety of a scene at rest, and WALL {} moves", w.id)});
    const lpfdm::Reservoir& r = scene.reservoir;
    if (r.on && r.to > -std::numeric_limits<double>::infinity() && r.to != r.level)
        d.push_back({r.pos, "--fos finds the factor of safety of a scene at rest, and the RESERVOIR's level moves (for the state after a drawdown: the reservoir at its last level, TO= left out)"});
    const lpfdm::Diagnostics w = lpfdm::fos_warnings(scene);  // (warnings: what is not verified)
    d.insert(d.end(), w.begin(), w.end());
    return d;
}

// The deck's outputs of one --fos trial, into DIR (created): the trial run again to its
// last step with the deck's OUTPUT cards, its provenance naming the reduced strengths as
// the --set options that reproduce it. False when a file cannot be written.
bool write_trial(const lpfdm::Scene& scene, const Options& opt, const std::string& text, const lpfdm::FosTrial& t, const std::string& dir, int nthreads) {
    lpfdm::Scene sc = lpfdm::strength_reduced(scene, t.F);
    sc.steps = t.steps;
    Options o = opt;
    o.outdir = dir;
    o.quiet = true;
    if (!make_dir(dir)) {
        std::fprintf(stderr, "lpfdm: error: cannot create the output directory '%s': %s\n", dir.c_str(), std::strerror(errno));
        return false;
    }
    lpfdm::Simulation sim(sc, opt.kernel);
    lpfdm::RunInfo run = run_info(sim, opt, text, nthreads);
    for (std::size_t k = 0; k < sc.materials.size(); ++k) {
        const lpfdm::Material &m = sc.materials[k], &was = scene.materials[k];
        if (m.model != lpfdm::Model::MohrCoulomb) continue;
        run.settings.push_back(fmt::format("MATERIAL{}.C={:.17g}", m.id, m.c));
        run.settings.push_back(fmt::format("MATERIAL{}.PHI={:.17g}", m.id, m.phi_deg));
        if (was.psi_deg != 0) run.settings.push_back(fmt::format("MATERIAL{}.PSI={:.17g}", m.id, m.psi_deg));
        if (was.tension >= 0) run.settings.push_back(fmt::format("MATERIAL{}.TENSION={:.17g}", m.id, m.tension));
    }
    run.steps = t.steps;
    Outputs out{o, sim, run, 0, {}, false};
    if (!out.open()) return false;
    double particle_steps = 0, wall = 0;
    Rest rest;
    return run_steps(sim, o, out, particle_steps, wall, rest) == 0;
}

// lpfdm --fos: the factor of safety (lpfdm::factor_of_safety), a line per trial unless
// --quiet, then the answer's line; the outputs of the bracket's two trials. The exit status.
int run_fos(const lpfdm::Scene& scene, const Options& opt, const std::string& text, int nthreads) {
    const auto t0 = std::chrono::steady_clock::now();
    lpfdm::FosOptions fo;
    fo.tol = opt.fos_tol;
    fo.kernel = opt.kernel;
    long n = 0;
    const lpfdm::FosResult r = lpfdm::factor_of_safety(scene, fo, [&](const lpfdm::FosTrial& t) {
        if (opt.quiet) return;
        std::printf("trial %ld: F = %.6g %s (unbalanced-force ratio %.3g; largest displacement %.3g m)\n", ++n, t.F,
                    t.trouble ? fmt::format("fails: numerical trouble at step {}", t.steps).c_str()
                    : t.stands ? fmt::format("stands: at rest at step {}", t.steps).c_str()
                    : fmt::format("fails: still moving after {} steps", t.steps).c_str(), t.ratio, t.moved);
        std::fflush(stdout);
    });
    const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (r.outcome == lpfdm::FosResult::NeverAtRest) {
        std::fprintf(stderr, "%s\n", lpfdm::Diagnostic{scene.step_pos, fmt::format(
            "--fos: even with unlimited strength (every MOHR material elastic) the scene is still moving after its {} steps "
            "(unbalanced-force ratio {:.3g}, at rest below {:g}): it needs DAMPING, or more steps (STEP, --steps), to come to rest",
            r.response_steps, r.ratio, kAtRest)}.str().c_str());
        return kExitBadInput;
    }
    // The digits of F that the tolerance makes: F to one place more than tol, the bracket to two.
    const int places = std::max(0, int(std::ceil(-std::log10(opt.fos_tol)))) ;
    const std::string how = fmt::format("{} trials of at most {} steps ({} response times of {} steps), {:.3g} s", r.trials.size(), r.budget,
                                        fo.responses, r.response_steps, secs);
    if (r.outcome == lpfdm::FosResult::FailsAtSmallest) {
        std::printf("factor of safety: below %g: the scene fails even at F = %g, with %g times the deck's strength (%s)\n", fo.smallest, r.fails_at, 1 / r.fails_at, how.c_str());
    } else if (r.outcome == lpfdm::FosResult::StandsAtLargest) {
        std::printf("factor of safety: above %g: the scene stands at F = %g, the largest trial (%s)\n", fo.largest, r.stands_at, how.c_str());
    } else {
        std::printf("factor of safety: %.*f (stands at %.*f, fails at %.*f, %s)\n", places, r.F, places + 1, r.stands_at, places + 1, r.fails_at, how.c_str());
    }
    std::fflush(stdout);
    bool ok = true;
    for (const auto& t : r.trials) {
        const bool last_standing = r.stands_at > 0 && t.F == r.stands_at, first_failing = r.fails_at > 0 && t.F == r.fails_at;
        if (!scene.outputs.empty() && (last_standing || first_failing))
            ok &= write_trial(scene, opt, text, t, opt.outdir + (last_standing ? "/stands" : "/fails"), nthreads);
    }
    if (!ok) return kExitBadInput;
    return r.outcome == lpfdm::FosResult::FailsAtSmallest ? kExitNumerical : 0;
}
}  // namespace

int main(int argc, char** argv) {
    Options opt;
    std::vector<std::string> cli_errors;  // every mistake, reported with the deck's
    if (const int done = read_command_line(argc, argv, opt, cli_errors); done >= 0) return done;
    if (opt.fos && !opt.restart.empty()) cli_errors.push_back("--fos runs each trial from the deck's start: it takes no --restart");
    lpfdm::Scene scene;
    std::string text;
    lpfdm::Diagnostics diags = read_and_check(opt, cli_errors, scene, text);
    const std::uint64_t digest = scene_digest(opt, scene, text);
    bool stop = !cli_errors.empty();
    for (const auto& e : cli_errors) std::fprintf(stderr, "lpfdm: error: %s\n", e.c_str());
    if (opt.fos && !stop) {  // (a scene that did not read cannot be asked)
        bool errors = false;
        for (const auto& d : diags) errors |= !d.warning;
        if (!errors) {
            lpfdm::Diagnostics f = fos_problems(scene);
            for (auto& d : f) d.warning = d.warning && !opt.strict;
            diags.insert(diags.end(), f.begin(), f.end());
            lpfdm::sort_diagnostics(diags);
        }
    }
    for (const auto& d : diags) {
        std::fprintf(stderr, "%s\n", d.str().c_str());
        stop |= !d.warning;
    }
    if (!cli_errors.empty()) std::fputs("lpfdm --help lists the options and the deck's cards\n", stderr);
    if (stop) return kExitBadInput;

#if defined(_OPENMP)
    // One thread unless asked: the output is the same for any number, and threads that
    // share busy cores with other programs wait at every barrier (57 times slower seen).
    if (opt.threads > 0) omp_set_num_threads(int(opt.threads));
    else if (!std::getenv("OMP_NUM_THREADS")) omp_set_num_threads(1);
    const int nthreads = omp_get_max_threads();
#else
    const int nthreads = 1;
#endif
    if (opt.fos) return run_fos(scene, opt, text, nthreads);
    lpfdm::Simulation sim(scene, opt.kernel);
    sim.set_profiling(opt.profile);
    const lpfdm::RunInfo run = run_info(sim, opt, text, nthreads);
    if (!opt.restart.empty()) {
        diags = lpfdm::read_state(opt.restart, sim, digest);
        if (diags.empty() && sim.step_count() >= scene.steps)
            diags = lpfdm::one_error(opt.restart, 0, 0, fmt::format("the state is at step {}, where the run ends (--steps N runs it further)", sim.step_count()));
        if (!diags.empty()) {
            for (const auto& d : diags) std::fprintf(stderr, "%s\n", d.str().c_str());
            return kExitBadInput;
        }
    }

    // --- outputs: NAME.part until complete ---
    if (!make_dir(opt.outdir)) {
        std::fprintf(stderr, "lpfdm: error: cannot create the output directory '%s': %s\n", opt.outdir.c_str(), std::strerror(errno));
        return kExitBadInput;
    }
    Outputs out{opt, sim, run, digest, {}, false};
    if (!out.open()) return kExitBadInput;
    double particle_steps = 0, wall = 0;
    Rest rest;
    const int status = run_steps(sim, opt, out, particle_steps, wall, rest);
    if (opt.profile) print_profile(sim, nthreads);
    if (!opt.quiet)
        std::printf("lpfdm: %ld steps, %zu points, %.3f s, %.3g particle-steps/s; mass inside %.9g, outflow %.9g, initial %.9g kg/m; kernel %s%s\n",
                    sim.step_count(), sim.points().size(), wall, wall > 0 ? particle_steps / wall : 0.0, sim.mass_inside(), sim.mass_outflow(),
                    sim.mass_initial(), kernel_said(sim, run).c_str(), status == kExitNumerical ? "" : rest.said().c_str());
    return status;
}
