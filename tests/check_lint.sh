#!/usr/bin/env bash
# Rules about the sources that a compiler does not check:
#   1. no unit test compares with doctest's own Approx. Its epsilon is relative to
#      1 + max(|x|, |v|) (the default scale 1), so for a quantity below one it is an
#      absolute tolerance: a displacement of 6.4e-3 m "within 1 %" passed 7e-5. Every
#      comparison goes through approx() of tests/common.hpp (scale 0: relative), and a
#      floor, where a value may be zero, is written with .scale(s) at the comparison.
#      doctest::Approx, an Approx( of the doctest namespace, and a `using` of it are
#      refused outside tests/common.hpp; and a floor is a rounding's size, a number
#      written out below 1e-5 (`.scale(1)` would make approx() doctest's Approx again:
#      an absolute tolerance that is not a check of its own is refused);
#   2. `make lpfdm` installs only what the program needs (fmt): the recipe of `deps`, as
#      `make -n` prints it, checks for and installs libfmt-dev alone.
# The rules are tested on themselves: a line of each kind written into a copy must be
# found.
#
# usage: tests/check_lint.sh EXE   (runs once, for the plain build of the program; EXE is
# not run). Last line "lint: N passed, M failed".
set -u
. "$(dirname "$0")/lib.sh"
cd "$(dirname "$0")/.." || exit 2
plain_build_only lint "${1:-}"
passed=0 failed=0
fail() { echo "FAIL lint $1"; failed=$((failed + 1)); }
tmp=$(mktemp -d) || exit 2
trap 'rm -rf "$tmp"' EXIT

# doctest's Approx used directly: `Approx(` not preceded by a letter, digit or `_` (so
# approx( and a name ending in Approx are not it), or `using doctest::Approx`.
bare_approx() {
    grep -HnE '(^|[^A-Za-z0-9_])Approx[[:space:]]*\(|using[[:space:]]+(namespace[[:space:]]+)?doctest(::Approx)?[[:space:]]*;' "$@" |
        grep -vE '^[^:]*:[0-9]+:[[:space:]]*//'
}
files=$(ls tests/*.cpp tests/*.hpp | grep -v '^tests/common.hpp$')
# shellcheck disable=SC2086
found=$(bare_approx $files)
if [ -z "$found" ]; then passed=$((passed + 1)); else
    fail "doctest's Approx used directly (use approx() of tests/common.hpp, scale 0):"
    echo "$found" | sed 's/^/  /'
fi
# the rule finds what it must, and not approx(
printf '%s\n' 'CHECK(x == Approx(1e-3).epsilon(0.01));' 'CHECK(x == doctest::Approx(v));' \
    'using doctest::Approx;' >"$tmp/bad.cpp"
printf '%s\n' 'CHECK(x == approx(1e-3).epsilon(0.01));' '// doctest::Approx(v) in a comment' \
    'CHECK(x == approx(v).epsilon(1e-12).scale(1e-6));' >"$tmp/good.cpp"
n_bad=$(bare_approx "$tmp/bad.cpp" | wc -l) n_good=$(bare_approx "$tmp/good.cpp" | wc -l)
if [ "$n_bad" -eq 3 ] && [ "$n_good" -eq 0 ]; then passed=$((passed + 1)); else
    fail "the Approx rule finds $n_bad of 3 bad lines and $n_good good ones"
fi

# a floor larger than a rounding's: .scale( holding anything but 0 or a number written
# out below 1e-5, one digit and an exponent of -6 or less (1e-6, 1E-9, 1e-300).
big_scale() {
    grep -HnoE '\.scale[[:space:]]*\([^)]*\)' "$@" | grep -vE '^[^:]*:[0-9]+:\.scale[[:space:]]*\([[:space:]]*(0(\.0*)?|[0-9](\.[0-9]*)?[eE]-([6-9]|[1-9][0-9]+))[[:space:]]*\)$'
}
# shellcheck disable=SC2086
found=$(big_scale $files)
if [ -z "$found" ]; then passed=$((passed + 1)); else
    fail "a floor of approx() of 1e-5 or more, or not a number (an absolute tolerance: check it on its own):"
    echo "$found" | sed 's/^/  /'
fi
printf '%s\n' 'CHECK(x == approx(v).scale(1));' 'CHECK(x == approx(v).scale(1e-3));' 'CHECK(x == approx(v).scale(tol));' \
    'CHECK(x == approx(v).scale(5e-5));' >"$tmp/bad_scale.cpp"
printf '%s\n' 'CHECK(x == approx(v).scale(1e-6));' 'CHECK(x == approx(v).epsilon(1e-15).scale(1e-300));' \
    'CHECK(x == approx(0.0).scale(1E-12));' 'CHECK(x == approx(v).scale(0));' >"$tmp/good_scale.cpp"
n_bad=$(big_scale "$tmp/bad_scale.cpp" | wc -l) n_good=$(big_scale "$tmp/good_scale.cpp" | wc -l)
if [ "$n_bad" -eq 4 ] && [ "$n_good" -eq 0 ]; then passed=$((passed + 1)); else
    fail "the floor rule finds $n_bad of 4 bad lines and $n_good good ones"
fi

# deps_of MAKEFILE: the packages the recipe of its `deps` (what `make lpfdm` runs first)
# checks for and installs, as make would run it.
deps_of() { make -s -n -f "$1" deps 2>/dev/null | grep -o 'for p in [^;]*;' | head -n 1 | sed -E 's/^for p in +//; s/ *;$//'; }
packages=$(deps_of Makefile)
if [ "$packages" = "libfmt-dev" ]; then passed=$((passed + 1)); else
    fail "make lpfdm installs '$packages', where the program needs only libfmt-dev"
fi
# the rule sees a deps that installs more
sed 's/^\(\tdeps\|\t@$(call install_missing,$(PACKAGES))\)$/\t@$(call install_missing,$(PACKAGES) $(PICTURE_PACKAGES))/' Makefile >"$tmp/Makefile"
more=$(deps_of "$tmp/Makefile")
if [ "$more" = "libfmt-dev gnuplot-nox" ]; then passed=$((passed + 1)); else
    fail "the package rule does not see a deps that installs gnuplot too (it read '$more')"
fi

echo "lint: $passed passed, $failed failed"
[ "$failed" -eq 0 ]
