#!/bin/bash
# Makes LinuxCNC's standalone interpreter `rs274` runnable for the tests:
# writes DIR/rs274, a wrapper that gives each run a private HOME, and
# DIR/share, a link to the folder that holds LinuxCNC's sample programs
# (DIR/share/{linuxcnc/ncfiles,doc/linuxcnc/examples}).
#
# An installed rs274 comes first: the one on PATH (Debian's linuxcnc-uspace
# puts it in /usr/bin; tools/install-deps.sh installs it), with the sample
# programs of its prefix (/usr/share). Otherwise the Debian packages
# (linuxcnc-uspace and the libraries it lacks on this machine) are
# downloaded with `apt-get download` and unpacked with `dpkg -x` into
# DIR/root, and the wrapper also sets LD_LIBRARY_PATH.
#
# usage: fetch_rs274.sh DIR
# exit 0: DIR/rs274 works; otherwise a one-line reason on stderr.
# These packages are GPL: they are used at test time only, never committed.
set -u
dir=${1:?usage: fetch_rs274.sh DIR}
mkdir -p "$dir/debs" "$dir/root" || exit 1
dir=$(cd "$dir" && pwd)
wrapper=$dir/rs274

# Several tests call this at once (ctest -j): one fetches, the others wait
# for it and then find rs274 working.
exec 9>"$dir/.lock"
flock 9

works() {
  [ -x "$wrapper" ] || return 1
  printf 'G0 X1\nM2\n' > "$dir/probe.ngc"
  printf 'T1 P1 Z0\n' > "$dir/probe.tbl"
  "$wrapper" -g -t "$dir/probe.tbl" "$dir/probe.ngc" 2>/dev/null | grep -q 'STRAIGHT_TRAVERSE(1.0000'
}

# Each run gets a HOME of its own: rs274 keeps its tool table in
# $HOME/.tool.mmap, which parallel runs would otherwise share and corrupt.
# Written beside and renamed over the old one: other tests may be running it.
# write_wrapper RS274 [LD_LIBRARY_PATH]
write_wrapper() {
  {
    echo '#!/bin/bash'
    [ -n "${2:-}" ] && echo "export LD_LIBRARY_PATH=\"$2\${LD_LIBRARY_PATH:+:\$LD_LIBRARY_PATH}\""
    cat <<WRAP
home=\$(mktemp -d "$dir/home.XXXXXX") || exit 1
HOME=\$home "$1" "\$@"
rc=\$?
rm -rf "\$home"
exit \$rc
WRAP
  } > "$wrapper.tmp"
  chmod +x "$wrapper.tmp"
  if cmp -s "$wrapper.tmp" "$wrapper"; then rm -f "$wrapper.tmp"; else mv -f "$wrapper.tmp" "$wrapper"; fi
}

# link_share FOLDER: DIR/share -> FOLDER (renamed over the old link).
link_share() {
  [ "$(readlink "$dir/share" 2>/dev/null)" = "$1" ] && return 0
  ln -sfn "$1" "$dir/share.tmp" && mv -fT "$dir/share.tmp" "$dir/share"
}

fetched_libs="$dir/root/usr/lib:$dir/root/usr/lib/x86_64-linux-gnu:$dir/root/lib/x86_64-linux-gnu"
use_fetched() { write_wrapper "$dir/root/usr/bin/rs274" "$fetched_libs" && link_share "$dir/root/usr/share"; }

# 1. An installed rs274 with its sample programs.
if installed=$(command -v rs274) && [ -x "$installed" ]; then
  installed=$(readlink -f "$installed")
  share=$(cd "$(dirname "$installed")/../share" 2>/dev/null && pwd)
  if [ -n "$share" ] && [ -d "$share/linuxcnc/ncfiles" ]; then
    write_wrapper "$installed" && link_share "$share"
    if works; then exit 0; fi
    echo "note: the installed $installed does not run here; fetching linuxcnc-uspace" >&2
  fi
fi
# 2. One fetched by an earlier run.
if [ -x "$dir/root/usr/bin/rs274" ]; then
  use_fetched
  if works; then exit 0; fi
fi
# 3. Fetch it. A wrapper left from an earlier run no longer counts.
rm -f "$wrapper" "$dir/share"
command -v apt-get >/dev/null && command -v dpkg >/dev/null || {
  echo "apt-get/dpkg not available: cannot fetch linuxcnc-uspace" >&2; exit 1; }

download() {  # download PACKAGE...: into debs/, retrying once after apt-get update
  (cd "$dir/debs" && apt-get download "$@" >/dev/null 2>&1) && return 0
  if [ "$(id -u)" = 0 ] && [ ! -e "$dir/.updated" ]; then
    apt-get update >/dev/null 2>&1 && touch "$dir/.updated"
    (cd "$dir/debs" && apt-get download "$@" >/dev/null 2>&1) && return 0
  fi
  return 1
}

unpack() { for deb in "$dir"/debs/*.deb; do dpkg -x "$deb" "$dir/root" || return 1; done; }

download linuxcnc-uspace libboost-python1.74.0 || {
  echo "apt-get download linuxcnc-uspace libboost-python1.74.0 failed (no package source?)" >&2
  exit 1; }
unpack || { echo "dpkg -x failed" >&2; exit 1; }

use_fetched

# Runtime libraries missing on this machine, by soname -> Debian package.
declare -A provider=(
  [libpython3.11.so.1.0]=libpython3.11 [libedit.so.2]=libedit2 [libtirpc.so.3]=libtirpc3
  [libexpat.so.1]=libexpat1 [libz.so.1]=zlib1g [libtinfo.so.6]=libtinfo6 [libbsd.so.0]=libbsd0
  [libmd.so.0]=libmd0 [libgssapi_krb5.so.2]=libgssapi-krb5-2 [libkrb5.so.3]=libkrb5-3
  [libk5crypto.so.3]=libk5crypto3 [libkrb5support.so.0]=libkrb5support0
  [libcom_err.so.2]=libcom-err2 [libkeyutils.so.1]=libkeyutils1
  [libboost_python311.so.1.74.0]=libboost-python1.74.0)
for round in 1 2 3; do
  missing=$(LD_LIBRARY_PATH="$fetched_libs" ldd "$dir/root/usr/bin/rs274" 2>/dev/null | awk '/not found/ {print $1}')
  [ -z "$missing" ] && break
  pkgs=()
  for lib in $missing; do
    if [ -n "${provider[$lib]:-}" ]; then pkgs+=("${provider[$lib]}"); else
      echo "rs274 needs $lib, which this script does not know how to fetch" >&2; exit 1; fi
  done
  download "${pkgs[@]}" && unpack || { echo "cannot fetch ${pkgs[*]}" >&2; exit 1; }
done

if works; then exit 0; fi
echo "rs274 was unpacked but does not run here (python3.11 runtime missing?)" >&2
exit 1
