#pragma once
// TLS for streaming to a TAK Server (its client port 8089): the client certificate and key (PEM,
// or the PKCS#12 files TAK Server's certificate tools hand out, with their password), the trust
// store (PEM or PKCS#12) that the server's certificate chain is verified against, always with the
// server's name or address, and an optional pin: the SHA-256 fingerprint of a certificate that
// must be part of the verified chain. OpenSSL (Debian's libssl); TLS 1.2 or newer.

#include <array>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

struct ssl_ctx_st;
struct ssl_st;

namespace hameritt::cop {

// A TLS setting that cannot be used: names the setting, the file and what is wrong with it.
class TlsConfigError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

// A handshake that did not end in a verified, accepted connection; what() is the reason.
class TlsHandshakeError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Where the credentials are. Either client_p12 or client_cert + client_key (or none of them: no
// client certificate, which a TAK Server's TLS input refuses).
struct TakTlsConfig {
  std::string client_p12;       // PKCS#12 with the client certificate and key
  std::string client_cert;      // PEM certificate (and its chain)
  std::string client_key;       // PEM private key, plain or encrypted
  std::string client_password;  // of client_p12, or of an encrypted client_key
  std::string trust_store;      // PEM bundle or PKCS#12 of CA certificates; empty: system CAs
  std::string trust_password;   // of a PKCS#12 trust store
  std::string pin_sha256;       // optional: hex SHA-256 of a certificate in the verified chain
  std::string server_name;      // optional: the name to verify instead of the URL's host

  bool hasClientCertificate() const { return !client_p12.empty() || !client_cert.empty(); }
  // Throws TlsConfigError for settings that contradict each other or a malformed pin (files
  // are read by TakTlsContext).
  void validate() const;
};

// The loaded credentials (an OpenSSL client context): read once, used for every connection.
class TakTlsContext {
 public:
  // Reads every file. Throws TlsConfigError naming the setting and the file: missing or
  // unreadable, not PEM/PKCS#12, a wrong password, a key that does not match the certificate, a
  // trust store without certificates.
  explicit TakTlsContext(const TakTlsConfig& config);
  ~TakTlsContext();
  TakTlsContext(const TakTlsContext&) = delete;
  TakTlsContext& operator=(const TakTlsContext&) = delete;

  const TakTlsConfig& config() const { return config_; }
  // The client certificate's subject (empty without one).
  const std::string& clientSubject() const { return client_subject_; }

 private:
  friend class TakTlsConnection;
  TakTlsConfig config_;
  ssl_ctx_st* ctx_ = nullptr;
  std::vector<std::array<unsigned char, 32>> pins_;
  std::string client_subject_;
};

// One TLS connection over a connected, non-blocking TCP socket (not owned).
class TakTlsConnection {
 public:
  // Handshakes within timeout_s, verifying the server's chain against the trust store and its
  // certificate against `host` (a DNS name or an IPv4 address; config().server_name wins when
  // set), then the pin. Under TLS 1.3 the server checks the client certificate after the
  // client's handshake ends: this waits (within timeout_s) for the server's first record, its
  // session ticket or its refusal. Throws TlsHandshakeError with the reason.
  TakTlsConnection(const TakTlsContext& context, int fd, const std::string& host, double timeout_s);
  ~TakTlsConnection();  // sends close_notify, best effort
  TakTlsConnection(const TakTlsConnection&) = delete;
  TakTlsConnection& operator=(const TakTlsConnection&) = delete;

  // Writes all of `data` (waiting at most timeout_s for the socket each time it is full); false
  // with `error` set when the connection failed.
  bool write(std::string_view data, double timeout_s, std::string& error);
  // Appends what the server sent and is readable now (never waits). False with `error` set when
  // the server closed the connection or it failed.
  bool readAvailable(std::string& out, std::string& error);
  // "TLSv1.3 TLS_AES_256_GCM_SHA384", for the log.
  std::string description() const;

 private:
  ssl_st* ssl_ = nullptr;
  int fd_ = -1;
  std::string early_;  // application data read while waiting for the server's first record
};

// A SHA-256 fingerprint given as hex (colons and case ignored); throws TlsConfigError naming
// `what` unless it is 64 hex digits.
std::array<unsigned char, 32> parseSha256(std::string_view hex, const std::string& what);

}  // namespace hameritt::cop
