# shellcheck shell=bash
# One selfsensed process at a time for a script that runs the daemon in real time: sourced by
# scripts/main_job.sh and scripts/heating_feedforward.sh after they set `root` (the source
# tree), `out` (OUT_DIR), `cli` and `daemon` (the built programs) and `config` (the path of the
# configuration copy under OUT_DIR/config). Defines start_daemon, stop_daemon and `ctl` (selfsense
# ctl on the daemon's socket), and an EXIT trap that stops a daemon still running.
: "${root:?}" "${out:?}" "${cli:?}" "${daemon:?}" "${config:?}"

# start_daemon SHIPPED_CONFIG [SED_SCRIPT]: the configuration with this run's paths (and the
# further edit SED_SCRIPT), checked, and selfsensed started on it; waits for its socket. The
# copy (`config`) is written into OUT_DIR/config, never into the source tree: models/ and plant/
# there are links to the shipped ones, so its relative paths (model: models/sim.yaml, plant:
# plant/daemon.yaml) resolve as the shipped file's do.
mkdir -p "$out/config"
ln -sfn "$root/config/models" "$out/config/models"
ln -sfn "$root/config/plant" "$out/config/plant"
pid=
start_daemon() {
  sed -e "s|directory: ../build/[a-z-]*/recordings|directory: $out/recordings|" \
    -e "s|path: ../build/[a-z-]*/control.sock|path: $out/control.sock|" \
    -e "s|prometheus_file: ../build/[a-z-]*/selfsensed.prom|prometheus_file: $out/selfsensed.prom|" \
    -e "${2:-}" "$1" >"$config"
  "$cli" check-config "$config"
  rm -f "$out/control.sock"  # the previous daemon's
  "$daemon" --config "$config" >>"$out/daemon.log" 2>&1 &
  pid=$!
  for _ in $(seq 100); do
    [ -S "$out/control.sock" ] && break
    sleep 0.1
  done
  [ -S "$out/control.sock" ] || {
    echo "FAILED: selfsensed did not open $out/control.sock: $(tail -5 "$out/daemon.log")" >&2
    exit 1
  }
}
# stop_daemon: SIGTERM, its exit status printed (the end-to-end test checks it).
stop_daemon() {
  kill -TERM "$pid"
  local status=0
  wait "$pid" || status=$?
  pid=
  rm -f "$config"
  echo "selfsensed exited with status $status"
}
cleanup() {
  [ -n "$pid" ] && kill -TERM "$pid" 2>/dev/null && wait "$pid" 2>/dev/null
  rm -f "$config"
}
trap cleanup EXIT
ctl() { "$cli" ctl --socket "$out/control.sock" "$@"; }
