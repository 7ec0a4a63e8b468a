#!/bin/sh
# halrun_private.sh MODULE_DIRS WORK_DIR COMMAND [ARG...]
#
# Runs a LinuxCNC command (`halrun -f FILE.hal`, `linuxcnc FILE.ini`) in
# WORK_DIR with the modules (*.so) of
# MODULE_DIRS (folders separated by ':') loadable by name, without touching
# the system, in private namespaces (unshare):
#   mount: LinuxCNC's module folder is replaced by WORK_DIR/modules, which
#          holds links to the stock modules and copies of MODULE_DIRS' ones;
#          /tmp is a fresh tmpfs (LinuxCNC's lock file);
#   ipc, net, pid: the session's HAL shared memory, rtapi_app's socket and
#          halrun's "realtime already running" check (ps -C rtapi_app) never
#          meet another session's, so tests may run side by side.
# rtapi_app refuses to run as root: COMMAND runs as the user `nobody`, in
# WORK_DIR (which nobody must be able to write), with HOME in the private
# /tmp. Needs root (to mount).
set -eu
if [ "$#" -lt 3 ]; then
  echo "usage: $0 MODULE_DIRS WORK_DIR COMMAND [ARG...]" >&2
  exit 2
fi
if [ -z "${TRUECUT_HALRUN_PRIVATE_INSIDE:-}" ]; then
  TRUECUT_HALRUN_PRIVATE_INSIDE=1 exec unshare --mount --ipc --net --pid --fork --mount-proc \
    --propagation private sh "$0" "$@"
fi
module_dirs=$1 work=$(cd "$2" && pwd -P)
shift 2
case $work/ in
  /tmp/*) echo "$0: WORK_DIR must not be in /tmp (a private /tmp hides it)" >&2; exit 2 ;;
esac
system_dir=$(dirname "$(command -v rtapi_app)")/../lib/linuxcnc/modules
system_dir=$(cd "$system_dir" && pwd -P)
mkdir -p "$work/stock" "$work/modules"
mount --bind "$system_dir" "$work/stock"
for m in "$work"/stock/*.so; do
  ln -sf "$m" "$work/modules/"
done
old_ifs=$IFS
IFS=:
for d in $module_dirs; do
  IFS=$old_ifs
  for m in "$d"/*.so; do
    [ -e "$m" ] && cp "$m" "$work/modules/"
  done
done
IFS=$old_ifs
mount --bind "$work/modules" "$system_dir"
mount -t tmpfs tmpfs /tmp
# HOME holds rtapi_app's socket, whose path must be short (108 bytes).
mkdir /tmp/home
chown nobody /tmp/home
cd "$work"
exec runuser -u nobody -- env HOME=/tmp/home "$@"
