# Shared by the program-level checks (sourced, not run).

# sanitizer_build EXE: true when EXE is a sanitizer build of the program (its name holds
# "san", as build/lpfdm-san's does).
sanitizer_build() { case $(basename "${1:-}") in *san*) return 0 ;; *) return 1 ;; esac; }

# plain_build_only LABEL ARG: a check that runs once, for the plain build of the program
# (its own builds, not the program's): for a sanitizer build, or no program, it says so,
# counts nothing and exits 0.
plain_build_only() {
    if [ -z "${2:-}" ] || sanitizer_build "$2"; then
        echo "$1: the check runs once, for the plain build of the program; nothing to do for ${2:-(no program)}"
        echo "$1: 0 passed, 0 failed"
        exit 0
    fi
}

# need_program LABEL ARGS...: the checks take one argument, the program. Sets exe to its
# absolute path (the checks change directory), or exits: status 2 with the usage when the
# arguments are wrong, status 1 with one failure and "LABEL: 0 passed, 1 failed" when it
# is not an executable program.
need_program() {
    local label=$1
    shift
    if [ $# -ne 1 ]; then
        echo "usage: $0 EXE" >&2
        exit 2
    fi
    exe=$1
    case $exe in
        */*) exe="$(cd "$(dirname "$exe")" 2>/dev/null && pwd)/$(basename "$exe")" ;;
        *) if [ -f "$exe" ]; then exe="$PWD/$exe"; else exe=$(command -v "$exe" || echo "$exe"); fi ;;
    esac
    if [ ! -x "$exe" ] || [ -d "$exe" ]; then
        echo "FAIL $1: not an executable program"
        echo "$label: 0 passed, 1 failed"
        exit 1
    fi
}
