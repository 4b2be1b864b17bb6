#!/bin/sh
# Make a private CA and the router's TLS certificate for a chronav deployment (openssl only).
#   deploy/make_certs.sh OUT_DIR ROUTER_NAME_OR_IP [MORE_NAMES_OR_IPS...] [--client NAME ...]
# e.g. deploy/make_certs.sh /etc/chronav/tls 10.0.0.1 chronav-server.local --client robot
# Writes ca.pem (give it to every host), ca.key (keep it offline), router.pem/router.key
# (router only) and, with --client NAME, NAME.pem/NAME.key for mutual TLS.
set -eu
[ $# -ge 2 ] || { echo "usage: $0 OUT_DIR ROUTER_NAME_OR_IP [NAMES...] [--client NAME ...]" >&2; exit 2; }
out=$1; shift
mkdir -p "$out"; umask 077
san=""; clients=""
while [ $# -gt 0 ]; do
  case $1 in
    --client) clients="$clients $2"; shift 2 ;;
    *) case $1 in
         *[!0-9.]*) san="$san,DNS:$1" ;;   # a host name
         *) san="$san,IP:$1" ;;            # an IPv4 address
       esac; shift ;;
  esac
done
san=${san#,}
[ -n "$san" ] || { echo "$0: give the router's host name or IP address" >&2; exit 2; }
[ -f "$out/ca.key" ] || openssl req -x509 -newkey ec -pkeyopt ec_paramgen_curve:prime256v1 -nodes -days 3650 \
  -keyout "$out/ca.key" -out "$out/ca.pem" -subj "/CN=chronav deployment CA" 2>/dev/null
sign() {  # sign NAME CN SAN
  openssl req -newkey ec -pkeyopt ec_paramgen_curve:prime256v1 -nodes -keyout "$out/$1.key" -out "$out/$1.csr" -subj "/CN=$2" 2>/dev/null
  printf 'subjectAltName=%s\n' "$3" > "$out/$1.ext"
  openssl x509 -req -in "$out/$1.csr" -CA "$out/ca.pem" -CAkey "$out/ca.key" -CAcreateserial \
    -days 825 -out "$out/$1.pem" -extfile "$out/$1.ext" 2>/dev/null
  rm -f "$out/$1.csr" "$out/$1.ext"
}
sign router "${san#*:}" "$san"
for name in $clients; do sign "$name" "$name" "DNS:$name"; done
echo "wrote $out: ca.pem router.pem router.key${clients:+ (clients:$clients)}"
