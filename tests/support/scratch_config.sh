# Sourced by shell tests that run a changed copy of a shipped configuration: the copy goes into
# the test's scratch directory, never into the source tree's config/.
#   link_shipped_config_dirs ROOT DIR   links ROOT/config/models and ROOT/config/plant into DIR, so
#                                       that a copy written into DIR resolves its paths relative
#                                       to its file (model: models/sim.yaml, plant:
#                                       plant/daemon.yaml) as the shipped one does
link_shipped_config_dirs() {
  ln -s "$1/config/models" "$2/models"
  ln -s "$1/config/plant" "$2/plant"
}
