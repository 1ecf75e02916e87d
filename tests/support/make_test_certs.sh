#!/usr/bin/env bash
# Makes the certificates the security tests use, in $1: a CA, a server certificate it signed for
# localhost, 127.0.0.1 and 10.79.0.1 (the server's address in the flood test's namespaces), a
# client certificate it signed (mTLS), and an unrelated CA that signed
# neither (a client trusting only that one must be refused). For the TLS diagnosis tests, also the
# ones that go wrong: a server and a client certificate that expired in 2020 and ones not valid
# before 2099 (both signed by the CA), and a client certificate the unrelated CA signed.
# Test material only: valid for 30 days from the build, EC P-256 keys (RSA 2048 with a second
# argument "rsa", for Mono, whose X509 classes read no EC keys; then also client.p12, the client's
# certificate and key as PKCS#12 with the SHA-1/3DES encryption older runtimes read), never used
# outside the build tree.
set -euo pipefail
out="$1"
algorithm="${2:-ec}"
mkdir -p "$out"
cd "$out"
days=30
if [ "$algorithm" = rsa ]; then
  key() { openssl genpkey -algorithm RSA -pkeyopt rsa_keygen_bits:2048 -out "$1" 2>/dev/null; }
else
  key() { openssl genpkey -algorithm EC -pkeyopt ec_paramgen_curve:P-256 -out "$1" 2>/dev/null; }
fi

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

# sign_dated CSR EXTFILE ISSUER START END OUT: `openssl x509 -req` (3.0) sets no validity start,
# so the dated ones go through a throwaway `openssl ca`.
sign_dated() {
  local db
  db=$(mktemp -d)
  touch "$db/index.txt"
  echo 01 > "$db/serial"
  printf '[ca]\ndefault_ca=dated\n[dated]\ndatabase=%s/index.txt\nnew_certs_dir=%s\nserial=%s/serial\ndefault_md=sha256\npolicy=any\nunique_subject=no\n[any]\ncommonName=supplied\n' \
    "$db" "$db" "$db" > "$db/ca.cnf"
  openssl ca -batch -notext -config "$db/ca.cnf" -cert "$3.pem" -keyfile "$3.key" -in "$1" \
    -extfile "$2" -startdate "$4" -enddate "$5" -out "$6" 2>/dev/null
  rm -rf "$db"
}
sign_dated server.csr server.ext ca 20200101000000Z 20200201000000Z server_expired.pem
sign_dated server.csr server.ext ca 20990101000000Z 20991231000000Z server_future.pem
sign_dated client.csr client.ext ca 20200101000000Z 20200201000000Z client_expired.pem
sign_dated client.csr client.ext ca 20990101000000Z 20991231000000Z client_future.pem
openssl x509 -req -in client.csr -CA other_ca.pem -CAkey other_ca.key -CAcreateserial -days "$days" \
  -extfile client.ext -out client_other_ca.pem 2>/dev/null
rm -f ./*.csr ./*.ext ./*.srl
if [ "$algorithm" = rsa ]; then
  openssl pkcs12 -export -in client.pem -inkey client.key -out client.p12 -passout pass: \
    -certpbe PBE-SHA1-3DES -keypbe PBE-SHA1-3DES -macalg sha1
fi
