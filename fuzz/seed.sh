#!/bin/sh
# Seeds fuzz/corpus/<target>/ from the fixtures (../shared/fixtures, or $GSPN_FIXTURES), the
# repository's plans and nets, and a few handwritten inputs. Only files under 32 KB are
# copied, so the committed corpus stays small. Run from anywhere:
#     sh fuzz/seed.sh [path/to/plan-runner]    # the binary, to record a journal seed
set -eu
cd "$(dirname "$0")/.."
fixtures="${GSPN_FIXTURES:-../shared/fixtures}"
corpus=fuzz/corpus
max=32768

# copy TARGET FILE...: each file under $max bytes, named after its path (no collisions).
copy() {
    target=$1; shift
    mkdir -p "$corpus/$target"
    for f in "$@"; do
        [ -f "$f" ] || continue
        [ "$(wc -c < "$f")" -le "$max" ] || continue
        name=$(printf '%s' "$f" | sed 's|^\.\./||; s|^\./||; s|/|_|g')
        cp "$f" "$corpus/$target/$name"
    done
}

# seed TARGET NAME TEXT: a handwritten input.
seed() {
    mkdir -p "$corpus/$1"
    printf '%s' "$3" > "$corpus/$1/$2"
}

# PIPE XML (the thesis format): every .xml that is not ISO PNML.
copy pipe_xml $(find "$fixtures" plans/nets -name '*.xml' | sort | xargs grep -L 'pnml.org' || true)
# ISO PNML (and VipTool's dialect).
copy pnml $(find "$fixtures" -name '*.pnml' | sort)
# GreatSPN projects.
copy pnpro $(find "$fixtures" plans/nets -name '*.PNPRO' | sort)
# Plans (checked against cyc3 by the target; the others exercise the TOML and its errors).
copy plan_toml $(find plans -name '*.toml' | sort)
seed plan_toml cyc3_full.toml 'net = "nets/cyc3_ss.PNPRO"
page = "cyc3"
seed = 3
time_scale = 0.0
[places.P1]
action = "go"
[[policy]]
marking = { P2 = 1 }
partial = true
choose = { t2 = 1.0 }
[stop]
when = "P1 + P3 >= 2 && !(P2 > 0)"
max_firings = 100
time_limit = 1e3
'
# Thesis execution inputs.
copy thesis_json $(find "$fixtures" -name '*.json' -path '*thesis*' | sort)
# Predicates over cyc3.
seed predicate simple 'P1 > 0 && P3 == 0'
seed predicate sums '2*P1 - P2 + 3 >= P3 || !(P2 != 1)'
seed predicate quoted '`P1` + (P2 * 2) < -1 || true'
seed predicate errors 'P1 = 1 && `P9'
# PNPRO expressions.
seed expr arith '2 * (N + 1) / 3 - -4'
seed expr funcs 'Max[Min[N, 3], Pow[2, 10]] + Binomial[5, 2] + Factorial[4]'
seed expr logic 'If[N > 3 && N != 4 || !False, Mod[7, 3], Sqrt[2.5e1]]'
seed expr numbers '1.000000e+00 + .5e1 + 7E-3'
# A journal of cyc3 (needs the binary: argument 1, else target/debug/plan-runner).
runner="${1:-target/debug/plan-runner}"
if [ -x "$runner" ]; then
    mkdir -p "$corpus/journal"
    "$runner" run plans/cyc3.toml --max-firings 30 --journal "$corpus/journal/cyc3_run.jsonl" > /dev/null
    # cyc3_run_with_records.jsonl (side records: a world's map and poses between the
    # events, as a run with simulated robots writes them) was written by hand from such a
    # journal; it is kept as it is.
else
    echo "no $runner: the journal corpus is left as it is" >&2
fi
du -sh "$corpus"
