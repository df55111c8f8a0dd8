#!/usr/bin/env bash
# Builds the Debian package with cpack and checks it: its fields, that Depends covers every
# shared library the program links, its files, and the program unpacked from it.
#   deb_test.sh BUILD_DIR WORK_DIR VERSION
set -euo pipefail
build=$1 work=$2 version=$3
fail() { echo "deb_test: $*" >&2; exit 1; }

rm -rf "$work"
mkdir -p "$work"
if ! (cd "$build" && cpack -G DEB -B "$work" --config CPackConfig.cmake) > "$work/cpack.log" 2>&1; then
  cat "$work/cpack.log"
  fail "cpack failed"
fi
debs=("$work"/zeroset_*.deb)
[[ ${#debs[@]} -eq 1 && -f ${debs[0]} ]] || fail "expected one zeroset_*.deb in $work"
deb=${debs[0]}
echo "package: $deb ($(du -h "$deb" | cut -f1))"

info=$(dpkg-deb --info "$deb")
echo "$info" | sed -n '/^ [A-Z][A-Za-z-]*: /,$p'
field() { echo "$info" | sed -n "s/^ $1: //p"; }
[[ $(field Package) == zeroset ]] || fail "Package is '$(field Package)'"
[[ $(field Version) == "$version" ]] || fail "Version is '$(field Version)', not $version"
for f in Maintainer Section Description Architecture; do
  [[ -n $(field "$f") ]] || fail "no $f field"
done
depends=$(field Depends)
[[ -n $depends ]] || fail "no Depends field"

# Every shared library the program needs directly comes from a package that Depends names.
contents=$(dpkg-deb --contents "$deb")
mkdir -p "$work/root"
dpkg-deb -x "$deb" "$work/root"
program=$work/root/usr/bin/zeroset
[[ -x $program ]] || fail "usr/bin/zeroset is missing"
while read -r needed; do
  path=$(ldd "$program" | awk -v lib="$needed" '$1 == lib && $2 == "=>" { print $3 }')
  [[ $needed == ld-linux* ]] && continue
  [[ -n $path ]] || fail "cannot resolve $needed"
  owner=""
  for candidate in "$path" "$(readlink -f "$path")" "/usr$path" "${path#/usr}"; do
    owner=$(dpkg -S "$candidate" 2>/dev/null | head -1 | cut -d: -f1) && [[ -n $owner ]] && break
  done
  [[ -n $owner ]] || fail "no Debian package owns $path ($needed)"
  [[ ", $depends," == *", $owner "* || ", $depends," == *", $owner,"* ||
     ", $depends," == *"| $owner "* || ", $depends," == *"| $owner,"* ]] ||
    fail "$needed comes from $owner, which Depends ($depends) does not name"
  echo "  $needed: $owner"
done < <(readelf -d "$program" | sed -n 's/.*(NEEDED).*\[\(.*\)\]/\1/p')

for f in ./usr/bin/zeroset ./usr/include/zeroset/types.h ./usr/include/zeroset/surface/catalog.h \
         ./usr/share/bash-completion/completions/zeroset ./usr/share/doc/zeroset/LICENSE; do
  grep -q " $f\$" <<<"$contents" || fail "the package has no $f"
done
for f in zerosetConfig.cmake zerosetConfigVersion.cmake zerosetTargets.cmake; do
  grep -q "/cmake/zeroset/$f\$" <<<"$contents" || fail "the package has no cmake/zeroset/$f"
done
grep -q '/libzeroset_mesh\.a$' <<<"$contents" || fail "the package has no libzeroset_mesh.a"
! grep -q '/zeroset/detail/' <<<"$contents" || fail "the package holds private detail headers"

out=$("$program" --version)
[[ $out == "zeroset $version" ]] || fail "zeroset --version printed '$out', not 'zeroset $version'"
out=$("$program" eval cayley --at 0.5,0.5,0.5 --json)
grep -q '"value": 4\.0' <<<"$out" || fail "the unpacked zeroset evaluated Cayley's cubic as: $out"
bash -n "$work/root/usr/share/bash-completion/completions/zeroset" ||
  fail "the packaged completion script is not valid bash"
echo "deb_test: $(basename "$deb") is complete; zeroset --version: $("$program" --version)"
