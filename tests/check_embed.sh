#!/usr/bin/env bash
# Embedding check: lpfdm.hpp compiles with LPFDM_NO_IO using only the C++17
# standard library (and Eigen, if present), with fmt out of reach, and tools/embed_example.cpp
# builds a scene in code, steps it, reads it back and plugs in a user constitutive model.
#
# usage: tests/check_embed.sh EXE
#
# EXE is the program of the run (./lpfdm or the sanitizer build); it is not run here, its
# name only chooses the flags: a name containing "san" compiles the example with
# AddressSanitizer and UBSan as well. Checks, one compile in all:
#   1. the example and a copy of lpfdm.hpp, alone in a temporary directory, compile with
#      -DLPFDM_NO_IO (no OpenMP) and link without -lfmt, while every fmt header name on
#      the include path is a file that stops the compile with #error;
#   2. that compile gives no warning with -Wall -Wextra -Wpedantic (an embedding project
#      may build with -Werror);
#   3. the compiler's -H list of included headers names no header under a fmt/ directory;
#   4. the trap works: the header preprocessed WITHOUT LPFDM_NO_IO hits it (or uses no fmt);
#   5. tools/embed_example.cpp is shorter than 100 lines;
#   6. the example runs, exits 0, and each of its own checks prints "ok";
#   7. the first rung of the teaching ladder, decks/freefall.deck, runs with EXE: the block
#      falls at g (kinetic energy (1/2) m (g t)^2 just before the impact) and the floor
#      first pushes at step 2433, when the lowest points enter the cells touching it;
#   8. (plain build) the example split in two units as stb's pattern asks: the unit
#      without LPFDM_IMPLEMENTATION compiles at -O2 in at most 1/8 of the time of the one
#      with it, links alone only to fail naming LPFDM_IMPLEMENTATION, and runs with it.
# One line per failure, and last "embed: N passed, M failed".
set -u
cd "$(dirname "$0")/.." || exit 2
exe=${1:-./lpfdm}
cxx=${CXX:-g++}
passed=0 failed=0
pass() { passed=$((passed + 1)); }
fail() { echo "FAIL $1"; failed=$((failed + 1)); }
finish() { echo "embed: $passed passed, $failed failed"; [ "$failed" -eq 0 ]; exit $?; }

tmp=$(mktemp -d) || exit 2
trap 'rm -rf "$tmp"' EXIT
mkdir -p "$tmp/src" "$tmp/trap/fmt"
cp lpfdm.hpp tools/embed_example.cpp "$tmp/src/" || { fail "cannot copy lpfdm.hpp and tools/embed_example.cpp"; finish; }

# Every fmt header name (those of the installed fmt and the usual set) becomes a trap.
names="args.h chrono.h color.h compile.h core.h format.h format-inl.h os.h ostream.h printf.h ranges.h std.h xchar.h"
for d in /usr/include/fmt /usr/local/include/fmt; do
    [ -d "$d" ] && names="$names $(cd "$d" && ls)"
done
for n in $names; do
    echo "#error \"fmt is out of reach: <fmt/$n> must not be needed with LPFDM_NO_IO\"" >"$tmp/trap/fmt/$n"
done
inc=(-I"$tmp/trap")
[ -d /usr/include/eigen3 ] && inc+=(-isystem /usr/include/eigen3)  # allowed by the contract, not required

# The sanitizer variant compiles without optimisation: the example's run is short, and
# the optimiser's own warnings are the plain variant's (-O1) to find; -O1 took 90 s here.
flags=(-std=c++17 -O1 -Wall -Wextra -Wpedantic -DLPFDM_NO_IO)
variant="-O1"
case $(basename "$exe") in
    *san*) flags=(-std=c++17 -O0 -Wall -Wextra -Wpedantic -DLPFDM_NO_IO -g1 -fsanitize=address,undefined -fno-sanitize-recover=all -fno-omit-frame-pointer)
           variant="ASan+UBSan, -O0" ;;
esac

# 1 + 2 + 3: one compile, with the list of included headers (-H) on stderr.
(cd "$tmp/src" && timeout 300 "$cxx" "${flags[@]}" "${inc[@]}" -H embed_example.cpp -o embed) >"$tmp/log" 2>&1
rc=$?
# Compiler messages without -H's header list and its include-guard advice.
awk '/^Multiple include guards may be useful for:/ { skip = 1; next }
     skip && /^\// { next } { skip = 0 } !/^\.+ / { print }' "$tmp/log" >"$tmp/messages"
if [ $rc -eq 0 ]; then
    pass
else
    fail "tools/embed_example.cpp with -DLPFDM_NO_IO ($variant, no -lfmt, fmt out of reach) does not compile:"
    head -n 20 "$tmp/messages"
fi
if [ $rc -eq 0 ] && ! grep -q 'warning:' "$tmp/messages"; then
    pass
elif [ $rc -eq 0 ]; then
    fail "lpfdm.hpp or the example gives warnings with -DLPFDM_NO_IO -Wall -Wextra -Wpedantic (no OpenMP):"
    grep 'warning:' "$tmp/messages" | sort -u | head -n 10
fi
headers=$(grep -E '^\.+ ' "$tmp/log" | sed -E 's/^\.+ //' | sort -u)
fmt_headers=$(grep -E '(^|/)fmt/' <<<"$headers")
if [ -n "$headers" ] && [ -z "$fmt_headers" ]; then
    pass
    echo "embed: $(wc -l <<<"$headers") headers included, none from fmt"
else
    fail "the LPFDM_NO_IO build includes fmt headers or listed none: ${fmt_headers:-(no -H list)}"
fi

# 3: the trap catches fmt when I/O is compiled in (preprocessing only).
if "$cxx" -std=c++17 "${inc[@]}" -E -x c++ "$tmp/src/lpfdm.hpp" -o /dev/null >"$tmp/log3" 2>&1; then
    pass  # the header uses no fmt even with I/O: nothing to catch
elif grep -q 'fmt is out of reach' "$tmp/log3"; then
    pass
else
    fail "preprocessing lpfdm.hpp without LPFDM_NO_IO failed for another reason:"; head -n 5 "$tmp/log3"
fi

# 4: short enough to read in one sitting.
lines=$(wc -l <tools/embed_example.cpp)
if [ "$lines" -lt 100 ]; then pass; else fail "tools/embed_example.cpp has $lines lines (must be < 100)"; fi

# 5: run it; its own checks print "ok  ..." or "FAIL ...".
if [ -x "$tmp/src/embed" ]; then
    ASAN_OPTIONS=detect_leaks=1 timeout 300 "$tmp/src/embed" >"$tmp/run" 2>&1
    rc=$?
    sed 's/^/  /' "$tmp/run"
    ok=$(grep -c '^ok ' "$tmp/run") bad=$(grep -c '^FAIL ' "$tmp/run")
    passed=$((passed + ok)); failed=$((failed + bad))
    if [ $rc -eq 0 ] && [ "$ok" -gt 0 ] && grep -q 'all checks passed' "$tmp/run"; then
        pass
    else
        fail "the embed example exited with status $rc ($ok checks ok, $bad failed)"
    fi
else
    fail "no embed example to run (the compile failed)"
fi

# 8: stb's pattern. The example as one file of a program of two: its copy without the
# define (declarations only, as every unit but one of an embedding program) and a unit
# that defines LPFDM_IMPLEMENTATION. Built at -O2 (plain build only), the declarations
# unit compiles in at most 1/8 of the implementation unit's time; linked alone it fails,
# and the linker names LPFDM_IMPLEMENTATION; linked with the other it runs as the example.
case $(basename "$exe") in
*san*) echo "embed: the two-unit build is the plain build's to check" ;;
*)
    split=$tmp/split
    mkdir -p "$split"
    grep -v '^#define LPFDM_IMPLEMENTATION' tools/embed_example.cpp >"$split/mine.cpp"
    printf '#define LPFDM_IMPLEMENTATION\n#include "lpfdm.hpp"\n' >"$split/impl.cpp"
    cp lpfdm.hpp "$split/"
    o2=(-std=c++17 -O2 -Wall -Wextra -Wpedantic -DLPFDM_NO_IO)
    compile() {  # compile FILE: its object; prints the processor seconds it took (user + system:
                 # make test runs other jobs beside this one, which stretch the wall time)
        local t
        t=$( { TIMEFORMAT='%3U %3S'; time (cd "$split" && "$cxx" "${o2[@]}" -c "$1.cpp" -o "$1.o" >>"$split/log" 2>&1); } 2>&1 ) || { echo fail; return; }
        awk -v t="$t" 'BEGIN { split(t, a, " "); printf "%.2f", a[1] + a[2] }'
    }
    eighth() { awk -v m="$1" -v i="$2" 'BEGIN { exit !(8 * m <= i) }'; }  # eighth T_UNIT T_IMPL: T_UNIT <= T_IMPL / 8
    t_mine=$(compile mine) t_impl=$(compile impl)
    if [ "$t_mine" = fail ] || [ "$t_impl" = fail ]; then
        fail "the two-unit build (-O2) does not compile: $(grep -m 3 -E 'error|warning' "$split/log" | tr '\n' ' ')"
    else
        echo "embed: -O2 compile (processor time): the declarations unit $t_mine s, the implementation unit $t_impl s"
        if eighth "$t_mine" "$t_impl"; then pass; else
            fail "the unit without LPFDM_IMPLEMENTATION took $t_mine s, more than 1/8 of the implementation unit's $t_impl s"; fi
        if (cd "$split" && "$cxx" mine.o -o alone) >"$split/link" 2>&1; then
            fail "the declarations unit linked without an implementation unit"
        elif grep -q 'LPFDM_IMPLEMENTATION' "$split/link"; then
            pass
        else
            fail "linked alone, the declarations unit fails without naming LPFDM_IMPLEMENTATION: $(head -n 3 "$split/link" | tr '\n' ' ')"
        fi
        if (cd "$split" && "$cxx" mine.o impl.o -o two) >>"$split/log" 2>&1 && "$split/two" >"$split/run" 2>&1 &&
           grep -q 'all checks passed' "$split/run"; then
            pass
        else
            fail "the two-unit example does not link or run: $(tail -n 2 "$split/run" 2>/dev/null | tr '\n' ' ')"
        fi
    fi
    # The whole public API, the deck reader and the writers included, from a unit without
    # the define: it compiles in at most 1/8 of the implementation unit's time, and links
    # against the implementation unit with I/O.
    cat >"$split/api.cpp" <<'API'
#include "lpfdm.hpp"
#include <cstdio>
int main() {
    lpfdm::Scene s;
    lpfdm::Unread u;
    lpfdm::Diagnostics d = lpfdm::read_deck_text("GRID 4 4 0.5\nMATERIAL 1 ELASTIC E=2E7 NU=0.25 RHO=2000\nCLUSTER 1 0 0 2 1\nFIX XY 0 0 2 0\nGRAVITY 0 -9.81\nDAMPING 0.8\nSTEP 1E-3 3\nEND\n", "api", s);
    d = lpfdm::parse_deck_text("GRID 4 4 0.5\n", "api", s, &u);
    lpfdm::Scene t;
    d = lpfdm::read_deck("decks/column.deck", t);
    d = lpfdm::validate(s, u); d = lpfdm::warnings(s); lpfdm::sort_diagnostics(d); d = lpfdm::one_error("f", 1, 1, "m");
    std::string text;
    d = lpfdm::load_file("decks/column.deck", text);
    lpfdm::Shake k; d = lpfdm::read_motion("decks/quake_pulse.txt", k);
    (void)lpfdm::record_problem(k); (void)lpfdm::apply_setting(s, "DAMPING.ALPHA", 0.5); lpfdm::refine(t, 1);
    (void)lpfdm::stable_dt(s); (void)lpfdm::count_points(s); (void)lpfdm::estimate_bytes(s, 1); (void)lpfdm::deck_help();
    (void)lpfdm::shortest(0.1); (void)lpfdm::nearest_name("GIRD", lpfdm::card_names()); (void)lpfdm::did_you_mean("GIRD", {"GRID"});
    (void)lpfdm::card_synopsis(lpfdm::kDeckCards[0]); (void)lpfdm::modes_of(s, lpfdm::Kernel::Fast); (void)lpfdm::fnv1a64(text);
    lpfdm::Simulation sim(s);
    sim.step(); sim.step_reference(); sim.cell_strains(); sim.update_points(); sim.map_to_lattice(); sim.nodal_forces(); sim.compensate(); sim.integrate();
    sim.set_wall_velocity(1, 0, 0); sim.set_wide(false); (void)sim.energy(); (void)sim.unbalanced_ratio(); (void)sim.by_id(); (void)sim.bytes_per_point();
    (void)sim.cell_holding(0.1, 0.1); (void)sim.strain_of_cell(0, 0); (void)sim.first_nonfinite_point(); int i, j; long q; sim.worst_node(i, j, q);
    (void)lpfdm::Simulation::phase_name(0); (void)lpfdm::Simulation::have_wide();
    sim.set_user_model(1, [](const lpfdm::StrainIncrement&, lpfdm::Stress&, lpfdm::PointState&) {});
    std::FILE* f = std::tmpfile();
    lpfdm::RunInfo run;
    lpfdm::write_provenance(f, sim, run); (void)lpfdm::history_columns(sim);
    lpfdm::write_points_header(f, sim, "api", &run); lpfdm::write_points_frame(f, sim, true);
    lpfdm::write_history_header(f, sim, "api"); lpfdm::write_history_row(f, sim);
    lpfdm::write_vtu(f, sim, sim.points().x, sim.points().y, false); lpfdm::write_vti(f, sim, true);
    lpfdm::write_pvd(f, {{lpfdm::vtu_frame_file("a", 1), 0.0}});
    const std::uint64_t h = lpfdm::state_digest(text, "");
    (void)lpfdm::write_state(f, sim, h); (void)lpfdm::read_state("/nonexistent", sim, h);
    std::fclose(f);
    std::puts("api: ok");
    return d.empty() ? 0 : 0;
}
API
    # (the implementation unit with I/O is compiled at -O0: only linked here, not timed; the
    # whole-API unit's time is held against the implementation unit without I/O, -O2,
    # the smaller of the two: at -O2 the one with I/O took 17.6 s, 6 more than without)
    printf '#define LPFDM_IMPLEMENTATION\n#include "lpfdm.hpp"\n' >"$split/impl_io.cpp"
    o2=(-std=c++17 -O0 -Wall -Wextra -Wpedantic)
    t_impl_io=$(compile impl_io)
    o2=(-std=c++17 -O2 -Wall -Wextra -Wpedantic)
    t_api=$(compile api)
    if [ "$t_api" = fail ] || [ "$t_impl_io" = fail ] || [ "$t_impl" = fail ]; then
        fail "the whole public API from a unit without LPFDM_IMPLEMENTATION (-O2, with I/O) does not compile: $(grep -m 3 -E 'error|warning' "$split/log" | tr '\n' ' ')"
    else
        echo "embed: -O2 compile (processor time), with I/O: a unit using the whole public API $t_api s (the implementation unit without I/O: $t_impl s)"
        if eighth "$t_api" "$t_impl"; then pass; else
            fail "the unit using the whole public API took $t_api s, more than 1/8 of the implementation unit's $t_impl s (without I/O)"; fi
        if (cd "$split" && "$cxx" api.o impl_io.o -o api -lfmt) >>"$split/log" 2>&1 && "$split/api" 2>&1 | grep -q 'api: ok'; then
            pass
        else
            fail "the whole-API unit does not link with the implementation unit, or does not run: $(grep -m 3 -E 'undefined|error' "$split/log" | tr '\n' ' ')"
        fi
    fi
    ;;
esac

# 7: the free-fall deck through the program (2600 of its steps: fall and impact).
if [ -x "$exe" ] && timeout 120 "$exe" -q -o "$tmp/ff" --steps 2600 decks/freefall.deck >"$tmp/ff.log" 2>&1; then
    # step time ke ...: first row where the floor reaction ry (the column so named) is not 0,
    # and ke of the row before it against (1/2) m (g dt n)^2, m = 2000 kg/m, dt = 2.5e-4 s.
    verdict=$(awk '/^# step / { for (k = 2; k <= NF; k++) if ($k == "ry") ry = k - 1 }
        !/^#/ && NF && $1 != "step" { if ($ry != 0) { n = $1; exit } prev_n = $1; prev_ke = $3 }
        END { v = 9.81 * 2.5e-4 * prev_n; ke = 1000 * v * v
              ok = (n >= 2432 && n <= 2434) && (prev_ke - ke) ^ 2 <= (1e-6 * ke) ^ 2
              printf "%s first contact at step %s (expected 2433), ke before it %.6g (free fall %.6g)\n", ok ? "ok" : "bad", n, prev_ke, ke }' \
        "$tmp/ff/freefall_history.txt" 2>/dev/null)
    echo "embed: freefall.deck: ${verdict#* }"
    if [ "${verdict%% *}" = ok ]; then pass; else fail "decks/freefall.deck: ${verdict:-no history written}"; fi
else
    fail "decks/freefall.deck does not run with $exe: $(head -n 3 "$tmp/ff.log" 2>/dev/null)"
fi
finish
