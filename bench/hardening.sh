#!/usr/bin/env bash
# Issue 17's reproducers on the shared data: for each hostile input or option,
# the exit code, the wall time, the number of stderr lines, the files left in
# the output folder (must be none unless the run succeeds) and the message.
#   [REFIT_SHARED_DATA=DIR] bash bench/hardening.sh [path/to/refit]
set -uo pipefail
cd "$(dirname "$0")/.."
R="$(realpath "${1:-build/release/tools/refit}")"
D="$(realpath "${REFIT_SHARED_DATA:-../shared/data}" 2>/dev/null || true)"
[ -f "$D/bodies/A_female.obj" ] || { echo "../shared/data is absent"; exit 77; }
W="$(mktemp -d)"; trap 'rm -rf "$W"' EXIT
G=$D/garments/skirt_on_A_female.obj; A=$D/bodies/A_female.obj; B=$D/bodies/F_heavier.obj
/usr/bin/python3 - "$D" "$W" <<'PY'
import sys
D, W = sys.argv[1], sys.argv[2]
def transform(src, dst, f, head=''):
    out = []
    for l in open(src).read().splitlines():
        if l.startswith('v '):
            p = [float(x) for x in l.split()[1:4]]
            out.append('v %r %r %r' % tuple(f(p)))
        else:
            out.append(l)
    open(dst, 'w').write(head + '\n'.join(out) + '\n')
transform(D + '/bodies/A_female.obj', W + '/A_mm.obj', lambda p: [10 * x for x in p])
transform(D + '/bodies/F_heavier.obj', W + '/B_mm.obj', lambda p: [10 * x for x in p])
transform(D + '/bodies/F_heavier.obj', W + '/B_point.obj', lambda p: [0, 100, 0])
transform(D + '/garments/skirt_on_A_female.obj', W + '/skirt_in.obj', lambda p: [x / 2.54 for x in p])
transform(D + '/garments/skirt_on_A_female.obj', W + '/skirt_m.obj', lambda p: [x / 100 for x in p])
g = open(D + '/garments/skirt_on_A_female.obj').read()
first = g.index('\nv ') + 1
open(W + '/skirt_bom.obj', 'w').write('\ufeff' + g[first:])
open(W + '/skirt_stmt.obj', 'w').write('bogus statement\n' + g)
end = g.index('\n', first)
open(W + '/huge_coords.obj', 'w').write(g[:first] + 'v 1e30 1e30 1e30' + g[end:])
open(W + '/huge.ply', 'w').write('ply\nformat ascii 1.0\nelement vertex 99999999999\nproperty float x\nend_header\n')
open(W + '/far.json', 'w').write('{"units":"cm","features":[{"name":"far","plane":{"point":[0,0,1000],"normal":[0,0,1]},'
    '"curve":{"kind":"bspline","degree":3,"closed":false,"control_points":[[0,0,1000],[10,0,1000],[20,0,1000],[30,5,1000]]},'
    '"samples":40}]}')
open(W + '/samples.json', 'w').write('{"units":"cm","features":[{"name":"hem","curve":{"kind":"boundary","near":[0,60,0]},'
    '"samples":100000}]}')
PY
run() {  # name, refit arguments...
  local name=$1; shift
  rm -rf "$W/out"; mkdir -p "$W/out"
  local t0 t1 rc
  t0=$(date +%s.%N)
  timeout 120 "$R" "$@" > "$W/stdout" 2> "$W/stderr"; rc=$?
  t1=$(date +%s.%N)
  printf "%-16s exit %-3s %6.2f s  %s stderr lines  left: %-14s %s\n" "$name" "$rc" "$(echo "$t1 - $t0" | bc)" \
    "$(wc -l < "$W/stderr")" "$(ls -A "$W/out" | tr '\n' ' ')" "$(head -c 160 "$W/stderr" | head -1)"
}
run huge_ply        resize --quiet --garment "$G" --from "$A" --to "$W/huge.ply" --out "$W/out/o.obj"
run huge_ply_batch  resize --quiet --garment "$G" --from "$A" --to "$B" "$W/huge.ply" --out-dir "$W/out"
run voxel_0.01      resize --quiet --garment "$G" --from "$A" --to "$B" --out "$W/out/o.obj" --voxel 0.01
run threads_-1      resize --quiet --garment "$G" --from "$A" --to "$B" --out "$W/out/o.obj" --threads -1
run samples_1e5     resize --quiet --garment "$G" --from "$A" --to "$B" --out "$W/out/o.obj" --features "$W/samples.json"
run mm_bodies       resize --quiet --garment "$G" --from "$W/A_mm.obj" --to "$W/B_mm.obj" --out "$W/out/o.obj"
run B_one_point     resize --quiet --garment "$G" --from "$A" --to "$W/B_point.obj" --out "$W/out/o.obj"
run B_in_mm         resize --quiet --garment "$G" --from "$A" --to "$W/B_mm.obj" --out "$W/out/o.obj"
run far_feature     resize --quiet --garment "$G" --from "$A" --to "$B" --out "$W/out/o.obj" --features "$W/far.json"
run clearance_1e6   resize --quiet --garment "$G" --from "$A" --to "$B" --out "$W/out/o.obj" --clearance 1e6
run clearance_nan   resize --quiet --garment "$G" --from "$A" --to "$B" --out "$W/out/o.obj" --clearance nan
run units_furlong   resize --quiet --garment "$G" --from "$A" --to "$B" --out "$W/out/o.obj" --units furlong --features "$W/far.json"
run huge_coords     resize --quiet --garment "$W/huge_coords.obj" --from "$A" --to "$B" --out "$W/out/o.obj"
run garment_in_in   resize --quiet --garment "$W/skirt_in.obj" --from "$A" --to "$B" --out "$W/out/o.obj"
run garment_in_m    resize --quiet --garment "$W/skirt_m.obj" --from "$A" --to "$B" --out "$W/out/o.obj"
run out_is_garment  resize --quiet --garment "$G" --from "$A" --to "$B" --out "$G"
run out_dev_null    resize --quiet --garment "$G" --from "$A" --to "$B" --out /dev/null
run report_eq_out   resize --quiet --garment "$G" --from "$A" --to "$B" --out "$W/out/x" --report "$W/out/x"
run report_no_dir   resize --quiet --garment "$G" --from "$A" --to "$B" --out "$W/out/o.obj" --report "$W/none/r.json"
run out_dir_file    resize --quiet --garment "$G" --from "$A" --to "$B" "$A" --out-dir "$W/far.json"
echo "-- should succeed (the warning on stderr, the output written):"
run bom_first_v     resize --quiet --garment "$W/skirt_bom.obj" --from "$A" --to "$B" --out "$W/out/o.obj" --stage warp
run unknown_stmt    resize --quiet --garment "$W/skirt_stmt.obj" --from "$A" --to "$B" --out "$W/out/o.obj" --stage warp
run identity        resize --quiet --garment "$G" --from "$A" --to "$A" --out "$W/out/o.obj"
cmp -s "$G" "$W/out/o.obj" && echo "identity: output byte-identical to the input" || echo "identity: OUTPUT DIFFERS"
