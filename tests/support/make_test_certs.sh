#!/usr/bin/env bash
# Makes the certificates the security tests use, in $1: a CA, a server certificate it signed for
# localhost, 127.0.0.1 and 10.79.0.1 (the server's address in the flood test's namespaces), a
# client certificate it signed (mTLS), and an unrelated CA that signed
# neither (a client trusting only that one must be refused). Test material only: valid for 30 days
# from the build, EC P-256 keys, never used outside the build tree.
set -euo pipefail
out="$1"
mkdir -p "$out"
cd "$out"
days=30
key() { openssl genpkey -algorithm EC -pkeyopt ec_paramgen_curve:P-256 -out "$1" 2>/dev/null; }

key ca.key
openssl req -x509 -new -key ca.key -days "$days" -subj "/CN=hapticd test CA" -out ca.pem
key other_ca.key
openssl req -x509 -new -key other_ca.key -days "$days" -subj "/CN=another CA" -out other_ca.pem

key server.key
openssl req -new -key server.key -subj "/CN=localhost" -out server.csr
printf 'subjectAltName=DNS:localhost,IP:127.0.0.1,IP:10.79.0.1\nextendedKeyUsage=serverAuth\n' > server.ext
openssl x509 -req -in server.csr -CA ca.pem -CAkey ca.key -CAcreateserial -days "$days" \
  -extfile server.ext -out server.pem 2>/dev/null

key client.key
openssl req -new -key client.key -subj "/CN=hapticd test client" -out client.csr
printf 'extendedKeyUsage=clientAuth\n' > client.ext
openssl x509 -req -in client.csr -CA ca.pem -CAkey ca.key -CAcreateserial -days "$days" \
  -extfile client.ext -out client.pem 2>/dev/null
rm -f ./*.csr ./*.ext ./*.srl
