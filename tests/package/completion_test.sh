#!/usr/bin/env bash
# The bash completion that `zeroset completion bash` writes: valid bash, and completing what a
# user types gives the subcommands, options, option values and file names it should.
#   completion_test.sh ZEROSET WORK_DIR
set -euo pipefail
zeroset=$1 work=$2
fail() { echo "completion_test: $*" >&2; exit 1; }

rm -rf "$work"
mkdir -p "$work/files/sub"
script=$work/zeroset.bash
"$zeroset" completion bash --output "$script"
bash -n "$script" || fail "the script is not valid bash"
[[ $("$zeroset" completion bash) == "$(cat "$script")" ]] || fail "--output and stdout differ"
if "$zeroset" completion fish > /dev/null 2>&1; then fail "'completion fish' was accepted"; fi

# shellcheck source=/dev/null
source "$script"
complete -p zeroset > /dev/null || fail "sourcing the script registered no completion"

# Completes the command line given as words; the last word is the one under the cursor.
complete_words() {
  COMP_WORDS=("$@")
  COMP_CWORD=$(($# - 1))
  COMP_LINE="$*"
  COMP_POINT=${#COMP_LINE}
  _zeroset
  printf '%s\n' "${COMPREPLY[@]}" | sort
}
expect() {
  local want=$1; shift
  local got
  got=$(complete_words "$@" | tr '\n' ' ' | sed 's/ $//')
  [[ $got == "$want" ]] || fail "completing '$*': got '$got', expected '$want'"
  echo "  '$*' -> $got"
}
contains() {
  local want=$1; shift
  complete_words "$@" | grep -qx -- "$want" || fail "completing '$*' does not offer $want"
}
lacks() {
  local unwanted=$1; shift
  ! complete_words "$@" | grep -qx -- "$unwanted" || fail "completing '$*' offers $unwanted"
}

cd "$work/files"
touch out.obj other.png
expect "mesh" zeroset me
expect "--resolution" zeroset mesh --res
expect "--resolution" zeroset mesh kummer --param mu=2 --res
expect "mesh" zeroset --threads 2 me
expect "mesh" zeroset -q me
expect "constrain fix" zeroset mesh kummer --boundary ""
expect "auto off" zeroset mesh kummer --improve ""
expect "kummer" zeroset render kum
expect "out.obj" zeroset mesh kummer -o ou
expect "out.obj" zeroset mesh kummer --output = ou
expect "sub" zeroset animate kummer -o s
expect "bash" zeroset completion ""
expect "" zeroset eval kummer --at ""
expect "auto dense sparse" zeroset mesh kummer --grid ""
contains list zeroset ""
contains --version zeroset --
contains cayley zeroset info ""
contains out.obj zeroset info ""
contains --show-singular zeroset mesh kummer --
lacks --frames zeroset mesh kummer --
lacks mesh zeroset mesh ""
echo "completion_test: all completions as expected"
