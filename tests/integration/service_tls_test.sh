#!/usr/bin/env bash
# TLS with certificates made here and now: a server with --tls-cert/--tls-key answers a CLI that
# trusts its certificate (--tls --ca) and no other; with --tls-client-ca it also requires the
# client's certificate (mutual TLS). Its HTTP endpoint (--http) serves HTTPS with the same files.
set -euo pipefail
source "$(dirname "$0")/test_database.sh" service_tls
fail() { echo "FAIL: $*" >&2; echo "--- server log" >&2; cat "$work/server.log" >&2; exit 1; }

# A self-signed server certificate for 127.0.0.1, a CA of clients and a client certificate it signs.
openssl req -x509 -newkey rsa:2048 -nodes -days 1 -subj /CN=127.0.0.1 -addext subjectAltName=IP:127.0.0.1 \
  -keyout "$work/server.key" -out "$work/server.pem" 2> /dev/null
openssl req -x509 -newkey rsa:2048 -nodes -days 1 -subj /CN=clients -keyout "$work/ca.key" -out "$work/ca.pem" 2> /dev/null
openssl req -newkey rsa:2048 -nodes -subj /CN=ci -keyout "$work/client.key" -out "$work/client.csr" 2> /dev/null
openssl x509 -req -in "$work/client.csr" -CA "$work/ca.pem" -CAkey "$work/ca.key" -CAcreateserial -days 1 \
  -out "$work/client.pem" 2> /dev/null
openssl req -x509 -newkey rsa:2048 -nodes -days 1 -subj /CN=127.0.0.1 -addext subjectAltName=IP:127.0.0.1 \
  -keyout "$work/other.key" -out "$work/other.pem" 2> /dev/null

start() {
  "$BATHYSLAM_SERVER_BIN" --db "$url" --migrate --listen 127.0.0.1:0 --http 127.0.0.1:0 --workers 0 --dev-tenant tls "$@" \
    > "$work/server.out" 2> "$work/server.log" &
  server_pid=$!
  for _ in $(seq 100); do grep -q "listening" "$work/server.out" && break; sleep 0.1; done
  BATHYSLAM_SERVER=$(sed -n 's/.*listening on //p' "$work/server.out")
  export BATHYSLAM_SERVER
  [ -n "$BATHYSLAM_SERVER" ] || fail "server did not start"
  http=$(sed -n 's/.*http on //p' "$work/server.out")
}
# GET /v1/jobs from the HTTP endpoint: URL, CA file, client certificate and key (optional).
https_get() {
  /usr/bin/python3 - "$@" <<'PY'
import ssl, sys, urllib.request
url, ca = sys.argv[1], sys.argv[2]
context = ssl.create_default_context(cafile=ca)
if len(sys.argv) > 3:
    context.load_cert_chain(sys.argv[3], sys.argv[4])
with urllib.request.urlopen(url + "/v1/jobs", context=context, timeout=30) as reply:
    assert reply.status == 200 and b'"jobs"' in reply.read()
PY
}
stop() { kill "$server_pid"; wait "$server_pid" || true; server_pid=""; }
refused() {  # the CLI with these options must fail with this in its message
  local expected=$1; shift
  if timeout 30 "$BATHYSLAM" jobs "$@" > /dev/null 2> "$work/err"; then fail "accepted: $*"; fi
  grep -q "$expected" "$work/err" || fail "$*: $(cat "$work/err")"
}

start --tls-cert "$work/server.pem" --tls-key "$work/server.key"
"$BATHYSLAM" jobs --tls --ca "$work/server.pem" > /dev/null || fail "TLS with the server's certificate trusted"
refused UNAVAILABLE                                 # plaintext to a TLS server
refused UNAVAILABLE --tls --ca "$work/other.pem"    # a certificate it does not trust
refused UNAVAILABLE --tls                           # the system's CAs do not know a self-signed one
case "$http" in https://*) ;; *) fail "the HTTP endpoint of a TLS server is not HTTPS: $http" ;; esac
https_get "$http" "$work/server.pem" || fail "HTTPS with the server's certificate trusted"
https_get "$http" "$work/other.pem" 2> /dev/null && fail "HTTPS accepted a certificate the client does not trust"
https_get "http://${http#https://}" "$work/server.pem" 2> /dev/null && fail "plain HTTP answered by a TLS endpoint"
stop

start --tls-cert "$work/server.pem" --tls-key "$work/server.key" --tls-client-ca "$work/ca.pem"
"$BATHYSLAM" jobs --tls --ca "$work/server.pem" --cert "$work/client.pem" --key "$work/client.key" > /dev/null ||
  fail "mutual TLS with a client certificate the CA signed"
refused UNAVAILABLE --tls --ca "$work/server.pem"   # no client certificate
refused UNAVAILABLE --tls --ca "$work/server.pem" --cert "$work/other.pem" --key "$work/other.key"
https_get "$http" "$work/server.pem" "$work/client.pem" "$work/client.key" || fail "HTTPS with a client certificate"
https_get "$http" "$work/server.pem" 2> /dev/null && fail "HTTPS without a client certificate accepted"
stop

# Half a configuration is refused at start, not served as plaintext.
if "$BATHYSLAM_SERVER_BIN" --db "$url" --listen 127.0.0.1:0 --tls-cert "$work/server.pem" 2> "$work/half.err"; then
  fail "a certificate without its key was accepted"
fi
grep -q -- "--tls-cert and --tls-key go together" "$work/half.err" || fail "$(cat "$work/half.err")"
echo "service tls: ok"
