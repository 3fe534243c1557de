# Sourced by the collision benchmarks (collide_bench.sh, collide_queries_bench.sh): the runs of
# one mesh and depth, shared so that both benchmarks run the same scenes.
#
# collide_runs VOBB OFF OUT MESH DEPTH SEEDS SUFFIX TREE... : for seeds 1..SEEDS, the dynamic
# scene (1,000 colliders, 10 s) and the static one (5,000 poses), all trees in one run, into
# OUT/run_MESH_DEPTH_MODE_sSEED<SUFFIX>.json; runs already there are kept.
collide_runs() {
  local vobb=$1 off=$2 out=$3 mesh=$4 depth=$5 seeds=$6 suffix=$7
  shift 7
  local seed mode run scene
  for seed in $(seq 1 "$seeds"); do
    for mode in dynamic static; do
      run=$out/run_${mesh}_${depth}_${mode}_s$seed$suffix.json
      [ -s "$run" ] && continue
      if [ "$mode" = dynamic ]; then scene="--colliders 1000 --seconds 10"; else scene="--static --colliders 5000"; fi
      # shellcheck disable=SC2086
      "$vobb" collide "$off" "$@" $scene --seed "$seed" --json -o "$run"
    done
  done
}
