// TLS settings: contradictions and malformed pins are refused before any file is read; each
// unusable file is named with what is wrong (missing, empty, not a certificate, wrong password,
// a key of another certificate); the good PEM and PKCS#12 sets load. The certificates are made
// by test/scripts/tak_pki.sh (openssl) into a temporary directory.
#include "hameritt/cop/tak_tls.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdlib>
#include <fstream>
#include <string>

namespace hameritt::cop {
namespace {

class TakTls : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    char tmpl[] = "/tmp/hameritt_tak_tls_XXXXXX";
    dir_ = mkdtemp(tmpl);
    const std::string cmd = "bash test/scripts/tak_pki.sh " + dir_ + " >/dev/null";
    ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
    std::ofstream(dir_ + "/empty.pem").close();
    std::ofstream(dir_ + "/garbage.p12") << "not a certificate";
  }
  static void TearDownTestSuite() { std::system(("rm -rf " + dir_).c_str()); }
  static std::string f(const std::string& name) { return dir_ + "/" + name; }

  // The TlsConfigError message of loading `c` ("" when it loads).
  static std::string loadError(const TakTlsConfig& c) {
    try {
      TakTlsContext context(c);
      return "";
    } catch (const TlsConfigError& e) {
      return e.what();
    }
  }
  static TakTlsConfig pem() {
    TakTlsConfig c;
    c.client_cert = f("client.pem");
    c.client_key = f("client-encrypted.key");
    c.client_password = "atakatak";
    c.trust_store = f("ca.pem");
    return c;
  }
  static TakTlsConfig p12() {
    TakTlsConfig c;
    c.client_p12 = f("client.p12");
    c.client_password = "atakatak";
    c.trust_store = f("truststore-root.p12");
    c.trust_password = "trustpass";
    return c;
  }
  static std::string dir_;
};
std::string TakTls::dir_;

#define EXPECT_CONTAINS(haystack, needle) \
  EXPECT_NE(std::string(haystack).find(needle), std::string::npos) << (haystack)

TEST_F(TakTls, GoodPemAndPkcs12SetsLoad) {
  EXPECT_EQ(loadError(pem()), "");
  EXPECT_EQ(loadError(p12()), "");
  TakTlsContext context(p12());
  EXPECT_CONTAINS(context.clientSubject(), "CN=client");
  TakTlsConfig legacy = p12();  // RC2/3DES, as older certificate tools write them
  legacy.client_p12 = f("client-legacy.p12");
  EXPECT_EQ(loadError(legacy), "");
  TakTlsConfig none;  // no client certificate, system CAs: loads (the server decides)
  EXPECT_EQ(loadError(none), "");
}

TEST_F(TakTls, ContradictionsAreRefusedNamingTheSetting) {
  TakTlsConfig c = p12();
  c.client_cert = f("client.pem");
  EXPECT_CONTAINS(loadError(c), "tls_client_p12");
  c = pem();
  c.client_key.clear();
  EXPECT_CONTAINS(loadError(c), "expected both");
  c = pem();
  c.pin_sha256 = "AB:CD";
  EXPECT_CONTAINS(loadError(c), "tls_pin_sha256 = 'AB:CD'");
  c.pin_sha256 = std::string(64, 'g');
  EXPECT_CONTAINS(loadError(c), "64 hex digits");
  c.pin_sha256 = std::string(64, 'a');
  EXPECT_EQ(loadError(c), "");
  c.server_name = "bad name";
  EXPECT_CONTAINS(loadError(c), "tls_server_name = 'bad name'");
}

TEST_F(TakTls, MissingEmptyAndForeignFilesAreNamed) {
  TakTlsConfig c = pem();
  c.trust_store = f("missing.pem");
  EXPECT_CONTAINS(loadError(c), "tls_trust_store '" + f("missing.pem") + "': cannot be read");
  c.trust_store = f("empty.pem");
  EXPECT_CONTAINS(loadError(c), "tls_trust_store '" + f("empty.pem") + "': the file is empty");
  c.trust_store = f("garbage.p12");
  EXPECT_CONTAINS(loadError(c), "tls_trust_store '" + f("garbage.p12") + "': not a PKCS#12");
  c = pem();
  c.client_cert = f("missing.pem");
  EXPECT_CONTAINS(loadError(c), "tls_client_cert '" + f("missing.pem") + "'");
  c = pem();
  c.client_key = f("client.pem");  // a certificate where the key belongs
  EXPECT_CONTAINS(loadError(c), "tls_client_key '" + f("client.pem") + "': no PEM private key");
  c = p12();
  c.client_p12 = f("missing.p12");
  EXPECT_CONTAINS(loadError(c), "tls_client_p12 '" + f("missing.p12") + "': cannot be read");
}

TEST_F(TakTls, WrongPasswordsAndKeysAreNamed) {
  TakTlsConfig c = p12();
  c.client_password = "wrong";
  EXPECT_CONTAINS(loadError(c), "tls_client_p12 '" + f("client.p12") + "': wrong password");
  c = p12();
  c.trust_password = "";
  EXPECT_CONTAINS(loadError(c),
                  "tls_trust_store '" + f("truststore-root.p12") + "': wrong password");
  c = pem();
  c.client_password = "wrong";
  EXPECT_CONTAINS(loadError(c), "tls_client_key '" + f("client-encrypted.key") +
                                    "': wrong password (tls_client_password)");
  c.client_password.clear();
  EXPECT_CONTAINS(loadError(c), "encrypted, and no password is set");
  c = pem();
  c.client_key = f("other-client.key");
  c.client_password.clear();
  EXPECT_CONTAINS(loadError(c), "tls_client_key '" + f("other-client.key") +
                                    "': does not match the certificate in tls_client_cert");
}

TEST(TakTlsPin, ParsesOpensslFingerprints) {
  const auto pin = parseSha256(
      "0A:1b:2C:3d:4E:5f:60:71:82:93:A4:B5:C6:D7:E8:F9:0a:1B:2c:3D:4e:5F:60:71:82:93:a4:b5:c6:"
      "d7:e8:f9",
      "pin");
  EXPECT_EQ(pin[0], 0x0a);
  EXPECT_EQ(pin[1], 0x1b);
  EXPECT_EQ(pin[31], 0xf9);
}

}  // namespace
}  // namespace hameritt::cop
