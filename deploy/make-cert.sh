#!/usr/bin/env bash
# Makes a self-signed TLS certificate for telegrasp-view --tls-cert/--tls-key, so that a headset on
# the LAN can open https://HOST:8765/xr (a browser gives WebXR only to secure pages). The headset's
# browser warns once about the unknown issuer: accept it ("Advanced" > "Proceed"), then the page
# and its WebSocket (wss://, same host and port) work.
#   deploy/make-cert.sh HOST [DIR]   HOST: the LAN host name or IP address the headset will type
#                                    (e.g. 192.168.1.20 or lab-pc.local); DIR: where to write
#                                    view-cert.pem and view-key.pem (default: the current folder)
# Then: telegrasp-view --drive --address 0.0.0.0 --tls-cert DIR/view-cert.pem --tls-key DIR/view-key.pem
set -euo pipefail
usage() { sed -n '2,9p' "$0" | sed 's/^# \{0,1\}//'; }
if [ $# -ge 1 ] && { [ "$1" = "-h" ] || [ "$1" = "--help" ]; }; then usage; exit 0; fi
if [ $# -lt 1 ] || [ $# -gt 2 ]; then usage >&2; exit 2; fi
host="$1"
dir="${2:-.}"
command -v openssl >/dev/null || { echo "make-cert: openssl is missing: run deploy/install-deps.sh" >&2; exit 1; }
if [[ "$host" =~ ^[0-9]+\.[0-9]+\.[0-9]+\.[0-9]+$ ]] || [[ "$host" == *:* ]]; then
  san="IP:$host"
elif [[ "$host" =~ ^[A-Za-z0-9]([A-Za-z0-9.-]*[A-Za-z0-9])?$ ]]; then
  san="DNS:$host"
else
  echo "make-cert: '$host' is neither an IP address nor a host name" >&2
  exit 2
fi
mkdir -p "$dir"
openssl req -x509 -newkey rsa:2048 -nodes -sha256 -days 825 -subj "/CN=$host" \
  -addext "subjectAltName=$san,DNS:localhost,IP:127.0.0.1" -addext "extendedKeyUsage=serverAuth" \
  -keyout "$dir/view-key.pem" -out "$dir/view-cert.pem" 2>/dev/null
chmod 600 "$dir/view-key.pem"
echo "make-cert: $dir/view-cert.pem and $dir/view-key.pem for $host (valid 825 days)"
echo "  telegrasp-view --drive --tls-cert $dir/view-cert.pem --tls-key $dir/view-key.pem"
echo "  then open https://$host:8765/xr?token=... (the URL telegrasp-view prints) on the headset"
