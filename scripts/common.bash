# What scripts/build and scripts/test share (sourced, not run).

# Runs a command as root: directly when this is root, else through sudo.
as_root() {
  if [[ $(id -u) -ne 0 ]]; then
    sudo "$@"
  else
    "$@"
  fi
}

# Installs the Debian packages given that are missing (apt, only when some are).
ensure_packages() {
  local missing=() p
  for p in "$@"; do
    if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
      missing+=("$p")
    fi
  done
  if ((${#missing[@]})); then
    echo "acvo: installing ${#missing[@]} missing Debian packages: ${missing[*]}"
    as_root apt-get update -qq
    as_root env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends \
      "${missing[@]}" >/dev/null
  fi
}

# A script's usage text: its header comment, from the second line to `set -euo pipefail`,
# without the leading "# ".
usage_of() {
  sed -n '2,/^set -euo/p' "$1" | sed -e '$d' -e 's/^# \{0,1\}//'
}
