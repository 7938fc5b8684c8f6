#!/bin/bash
# Makes the certificates of the TAK TLS tests into DIR with the openssl tool, as a TAK Server's
# certificate tools lay them out: a CA, a server certificate for 127.0.0.1 and localhost (and an
# expired one), a
# client certificate (PEM, an encrypted PEM key and a PKCS#12 with a password), the trust store
# (PEM and PKCS#12), and for the negative cases a second CA with its own server and client
# certificates that the first CA does not know.
#   test/scripts/tak_pki.sh DIR        (passwords: client "atakatak", trust store "trustpass")
set -euo pipefail
D="$1"
mkdir -p "$D"
cd "$D"
days=30
ec() { openssl genpkey -algorithm EC -pkeyopt ec_paramgen_curve:P-256 -out "$1" 2>/dev/null; }
ca() {  # NAME
  ec "$1.key"
  openssl req -x509 -new -key "$1.key" -days $days -subj "/CN=$1 test CA" \
    -addext basicConstraints=critical,CA:TRUE -addext keyUsage=critical,keyCertSign,cRLSign \
    -out "$1.pem" 2>/dev/null
}
leaf() {  # NAME CA EXT
  ec "$1.key"
  openssl req -new -key "$1.key" -subj "/CN=$1" -out "$1.csr" 2>/dev/null
  printf '%s\n' "$3" >"$1.ext"
  openssl x509 -req -in "$1.csr" -CA "$2.pem" -CAkey "$2.key" -CAcreateserial -days $days \
    -extfile "$1.ext" -out "$1.pem" 2>/dev/null
}
ca ca
ca other-ca
server_ext='subjectAltName=IP:127.0.0.1,DNS:localhost
extendedKeyUsage=serverAuth'
client_ext='extendedKeyUsage=clientAuth'
leaf server ca "$server_ext"
leaf client ca "$client_ext"
leaf other-server other-ca "$server_ext"
leaf other-client other-ca "$client_ext"
# The server's key with a certificate that expired a day ago (-days -1: notAfter before now).
cp server.key expired-server.key
openssl x509 -req -in server.csr -CA ca.pem -CAkey ca.key -CAcreateserial -days -1 \
  -extfile server.ext -out expired-server.pem 2>/dev/null
# The client's key encrypted, and its PKCS#12 (certificate, key and CA) with a password.
openssl pkey -in client.key -aes256 -passout pass:atakatak -out client-encrypted.key
openssl pkcs12 -export -in client.pem -inkey client.key -certfile ca.pem -name client \
  -passout pass:atakatak -out client.p12
# The same with the RC2/3DES encryption of older certificate tools (OpenSSL's legacy provider).
openssl pkcs12 -export -legacy -in client.pem -inkey client.key -certfile ca.pem -name client \
  -passout pass:atakatak -out client-legacy.p12
# The trust store as a PKCS#12 of the CA certificate alone.
openssl pkcs12 -export -nokeys -in ca.pem -passout pass:trustpass -out truststore-root.p12
# SHA-256 fingerprints (hex, colons) for the pin.
for c in ca other-ca; do
  openssl x509 -in $c.pem -noout -fingerprint -sha256 | sed 's/^.*=//' >$c.sha256
done
