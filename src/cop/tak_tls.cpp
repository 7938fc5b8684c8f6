#include "hameritt/cop/tak_tls.h"

#include <arpa/inet.h>
#include <openssl/err.h>
#include <openssl/evp.h>
#include <openssl/pem.h>
#include <openssl/pkcs12.h>
#include <openssl/provider.h>
#include <openssl/ssl.h>
#include <openssl/x509.h>
#include <openssl/x509v3.h>
#include <poll.h>

#include <cctype>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <memory>
#include <mutex>
#include <sstream>

namespace hameritt::cop {
namespace {

using Clock = std::chrono::steady_clock;

// The reasons in OpenSSL's error queue (emptied), "lib: reason; ...".
std::string opensslErrors() {
  std::string out;
  while (const unsigned long e = ERR_get_error()) {
    const char* reason = ERR_reason_error_string(e);
    const char* lib = ERR_lib_error_string(e);
    if (!out.empty()) out += "; ";
    out += std::string(lib ? lib : "openssl") + ": " +
           (reason ? reason : "error " + std::to_string(ERR_GET_REASON(e)));
  }
  return out.empty() ? "no OpenSSL reason" : out;
}

std::string readFile(const std::string& what, const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in)
    throw TlsConfigError(what + " '" + path + "': cannot be read (" + std::strerror(errno) + ")");
  std::ostringstream s;
  s << in.rdbuf();
  if (s.str().empty()) throw TlsConfigError(what + " '" + path + "': the file is empty");
  return s.str();
}

bool isPem(const std::string& data) { return data.find("-----BEGIN ") != std::string::npos; }

std::string subjectOf(X509* cert) {
  char buf[512];
  X509_NAME_oneline(X509_get_subject_name(cert), buf, sizeof buf);
  return buf;
}

// PKCS#12 files from older tools encrypt with RC2 or 3DES: OpenSSL 3 reads them with its legacy
// provider, loaded on the first such file and unloaded at exit.
bool loadLegacyProvider() {
  struct Legacy {
    OSSL_PROVIDER* provider = OSSL_PROVIDER_try_load(nullptr, "legacy", 1);
    ~Legacy() {
      if (provider) OSSL_PROVIDER_unload(provider);
    }
  };
  static std::mutex mutex;
  std::lock_guard<std::mutex> lock(mutex);
  static const Legacy legacy;
  ERR_clear_error();
  return legacy.provider != nullptr;
}

struct P12Contents {
  EVP_PKEY* key = nullptr;
  X509* cert = nullptr;
  STACK_OF(X509) * ca = nullptr;
  ~P12Contents() {
    EVP_PKEY_free(key);
    X509_free(cert);
    sk_X509_pop_free(ca, X509_free);
  }
};

void readP12(const std::string& what, const std::string& path, const std::string& password,
             P12Contents& out) {
  const std::string data = readFile(what, path);
  ERR_clear_error();
  const unsigned char* p = reinterpret_cast<const unsigned char*>(data.data());
  std::unique_ptr<PKCS12, decltype(&PKCS12_free)> p12(
      d2i_PKCS12(nullptr, &p, static_cast<long>(data.size())), PKCS12_free);
  if (!p12)
    throw TlsConfigError(what + " '" + path + "': not a PKCS#12 file (" + opensslErrors() + ")");
  if (!PKCS12_verify_mac(p12.get(), password.c_str(), -1)) {
    ERR_clear_error();
    throw TlsConfigError(what + " '" + path + "': wrong password (the PKCS#12 integrity check " +
                         "fails with the password given)");
  }
  if (!PKCS12_parse(p12.get(), password.c_str(), &out.key, &out.cert, &out.ca)) {
    const std::string why = opensslErrors();
    if (!loadLegacyProvider() ||
        !PKCS12_parse(p12.get(), password.c_str(), &out.key, &out.cert, &out.ca))
      throw TlsConfigError(what + " '" + path + "': cannot be decrypted (" + why + ")");
  }
}

int passwordCallback(char* buf, int size, int, void* user) {
  const std::string& pw = *static_cast<const std::string*>(user);
  if (pw.empty() || static_cast<int>(pw.size()) > size) return -1;  // never prompt
  std::memcpy(buf, pw.data(), pw.size());
  return static_cast<int>(pw.size());
}

bool waitFd(int fd, short events, Clock::time_point deadline) {
  const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now());
  if (left.count() <= 0) return false;
  pollfd p{fd, events, 0};
  return ::poll(&p, 1, static_cast<int>(left.count())) > 0;
}

// The peer closed the TCP connection without a TLS alert (OpenSSL 3 reports it as an error).
bool peerClosed(int ssl_error) {
  if (ssl_error == SSL_ERROR_ZERO_RETURN) return true;
  const unsigned long e = ERR_peek_error();
  if (ssl_error == SSL_ERROR_SYSCALL && e == 0) return true;
  return ssl_error == SSL_ERROR_SSL && ERR_GET_LIB(e) == ERR_LIB_SSL &&
         ERR_GET_REASON(e) == SSL_R_UNEXPECTED_EOF_WHILE_READING;
}

std::string seconds(double s) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", s);
  return buf;
}

bool isIpv4(const std::string& host) {
  in_addr a{};
  return inet_pton(AF_INET, host.c_str(), &a) == 1;
}

}  // namespace

std::array<unsigned char, 32> parseSha256(std::string_view hex, const std::string& what) {
  std::string digits;
  for (const char c : hex)
    if (c != ':' && c != ' ') digits += c;
  std::array<unsigned char, 32> out{};
  const auto fail = [&] {
    return TlsConfigError(what + " = '" + std::string(hex) +
                          "' (expected a SHA-256 fingerprint: 64 hex digits, colons allowed, as "
                          "`openssl x509 -noout -fingerprint -sha256` prints it)");
  };
  if (digits.size() != 64) throw fail();
  for (size_t i = 0; i < 32; ++i) {
    unsigned v = 0;
    for (size_t k = 0; k < 2; ++k) {
      const char c = static_cast<char>(std::tolower(static_cast<unsigned char>(digits[2 * i + k])));
      if (!std::isxdigit(static_cast<unsigned char>(c))) throw fail();
      v = v * 16 + static_cast<unsigned>(
                       std::isdigit(static_cast<unsigned char>(c)) ? c - '0' : c - 'a' + 10);
    }
    out[i] = static_cast<unsigned char>(v);
  }
  return out;
}

void TakTlsConfig::validate() const {
  if (!client_p12.empty() && (!client_cert.empty() || !client_key.empty()))
    throw TlsConfigError("tls_client_p12 = '" + client_p12 +
                         "' and tls_client_cert/tls_client_key are both set (expected the "
                         "PKCS#12 file or the PEM pair, not both)");
  if (client_cert.empty() != client_key.empty())
    throw TlsConfigError(std::string("tls_client_cert = '") + client_cert +
                         "', tls_client_key = '" + client_key +
                         "' (expected both, the PEM certificate and its private key, or neither)");
  if (!pin_sha256.empty()) parseSha256(pin_sha256, "tls_pin_sha256");
  for (const char c : server_name)
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '.' && c != '-')
      throw TlsConfigError("tls_server_name = '" + server_name +
                           "' (expected a DNS name or a dotted IPv4 address)");
}

TakTlsContext::TakTlsContext(const TakTlsConfig& config) : config_(config) {
  config_.validate();
  ERR_clear_error();
  ctx_ = SSL_CTX_new(TLS_client_method());
  if (!ctx_) throw TlsConfigError("TLS: cannot create a client context (" + opensslErrors() + ")");
  try {
    SSL_CTX_set_min_proto_version(ctx_, TLS1_2_VERSION);
    SSL_CTX_set_verify(ctx_, SSL_VERIFY_PEER, nullptr);
    SSL_CTX_set_mode(ctx_, SSL_MODE_ENABLE_PARTIAL_WRITE | SSL_MODE_ACCEPT_MOVING_WRITE_BUFFER);

    // Trust store.
    if (config_.trust_store.empty()) {
      if (!SSL_CTX_set_default_verify_paths(ctx_))
        throw TlsConfigError("TLS: the system's CA certificates cannot be loaded (" +
                             opensslErrors() + ")");
    } else {
      const std::string what = "tls_trust_store";
      const std::string data = readFile(what, config_.trust_store);
      X509_STORE* store = SSL_CTX_get_cert_store(ctx_);
      int added = 0;
      if (isPem(data)) {
        std::unique_ptr<BIO, decltype(&BIO_free)> bio(
            BIO_new_mem_buf(data.data(), static_cast<int>(data.size())), BIO_free);
        while (X509* cert = PEM_read_bio_X509(bio.get(), nullptr, nullptr, nullptr)) {
          added += X509_STORE_add_cert(store, cert) == 1;
          X509_free(cert);
        }
        ERR_clear_error();  // the end of the file reads as an error
      } else {
        P12Contents p12;
        readP12(what, config_.trust_store, config_.trust_password, p12);
        if (p12.cert) added += X509_STORE_add_cert(store, p12.cert) == 1;
        for (int i = 0; p12.ca && i < sk_X509_num(p12.ca); ++i)
          added += X509_STORE_add_cert(store, sk_X509_value(p12.ca, i)) == 1;
      }
      if (added == 0)
        throw TlsConfigError(what + " '" + config_.trust_store +
                             "': holds no certificate (expected the CA certificates, PEM or "
                             "PKCS#12, that signed the server's certificate)");
    }

    // Client certificate.
    X509* leaf = nullptr;
    if (!config_.client_p12.empty()) {
      const std::string what = "tls_client_p12";
      P12Contents p12;
      readP12(what, config_.client_p12, config_.client_password, p12);
      if (!p12.cert || !p12.key)
        throw TlsConfigError(what + " '" + config_.client_p12 + "': holds no " +
                             (p12.cert ? "private key" : "certificate") +
                             " (expected the client's certificate and key, e.g. user.p12)");
      if (SSL_CTX_use_certificate(ctx_, p12.cert) != 1 ||
          SSL_CTX_use_PrivateKey(ctx_, p12.key) != 1)
        throw TlsConfigError(what + " '" + config_.client_p12 + "': " + opensslErrors());
      for (int i = 0; p12.ca && i < sk_X509_num(p12.ca); ++i)
        SSL_CTX_add1_chain_cert(ctx_, sk_X509_value(p12.ca, i));
      if (SSL_CTX_check_private_key(ctx_) != 1)
        throw TlsConfigError(what + " '" + config_.client_p12 +
                             "': the key does not match the certificate");
    } else if (!config_.client_cert.empty()) {
      readFile("tls_client_cert", config_.client_cert);
      if (SSL_CTX_use_certificate_chain_file(ctx_, config_.client_cert.c_str()) != 1)
        throw TlsConfigError("tls_client_cert '" + config_.client_cert + "': no PEM certificate (" +
                             opensslErrors() + ")");
      const std::string key = readFile("tls_client_key", config_.client_key);
      std::unique_ptr<BIO, decltype(&BIO_free)> bio(
          BIO_new_mem_buf(key.data(), static_cast<int>(key.size())), BIO_free);
      ERR_clear_error();
      EVP_PKEY* pkey = PEM_read_bio_PrivateKey(bio.get(), nullptr, passwordCallback,
                                               const_cast<std::string*>(&config_.client_password));
      if (!pkey) {
        const bool encrypted = key.find("ENCRYPTED") != std::string::npos;
        throw TlsConfigError("tls_client_key '" + config_.client_key + "': " +
                             (encrypted ? (config_.client_password.empty()
                                               ? std::string("encrypted, and no password is set "
                                                             "(tls_client_password)")
                                               : std::string("wrong password (tls_client_"
                                                             "password) or damaged key"))
                                        : "no PEM private key (" + opensslErrors() + ")"));
      }
      const int used = SSL_CTX_use_PrivateKey(ctx_, pkey);
      EVP_PKEY_free(pkey);
      if (used != 1 || SSL_CTX_check_private_key(ctx_) != 1) {
        ERR_clear_error();
        throw TlsConfigError("tls_client_key '" + config_.client_key +
                             "': does not match the certificate in tls_client_cert '" +
                             config_.client_cert + "'");
      }
    }
    leaf = SSL_CTX_get0_certificate(ctx_);
    if (leaf) client_subject_ = subjectOf(leaf);
    if (!config_.pin_sha256.empty()) pins_.push_back(parseSha256(config_.pin_sha256, "pin"));
  } catch (...) {
    SSL_CTX_free(ctx_);
    ctx_ = nullptr;
    throw;
  }
}

TakTlsContext::~TakTlsContext() { SSL_CTX_free(ctx_); }

TakTlsConnection::TakTlsConnection(const TakTlsContext& context, int fd, const std::string& host,
                                   double timeout_s)
    : fd_(fd) {
  ERR_clear_error();
  ssl_ = SSL_new(context.ctx_);
  if (!ssl_) throw TlsHandshakeError("TLS: SSL_new failed (" + opensslErrors() + ")");
  const std::string name = context.config_.server_name.empty() ? host : context.config_.server_name;
  X509_VERIFY_PARAM* param = SSL_get0_param(ssl_);
  X509_VERIFY_PARAM_set_hostflags(param, X509_CHECK_FLAG_NO_PARTIAL_WILDCARDS);
  const bool ip = isIpv4(name);
  if ((ip ? X509_VERIFY_PARAM_set1_ip_asc(param, name.c_str())
          : X509_VERIFY_PARAM_set1_host(param, name.c_str(), 0)) != 1) {
    SSL_free(ssl_);
    throw TlsHandshakeError("TLS: cannot verify against the name '" + name + "'");
  }
  if (!ip) SSL_set_tlsext_host_name(ssl_, name.c_str());
  SSL_set_fd(ssl_, fd);
  const auto deadline = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                           std::chrono::duration<double>(timeout_s));
  const auto fail = [&](const std::string& reason) {
    SSL_free(ssl_);
    ssl_ = nullptr;
    return TlsHandshakeError(reason);
  };
  while (true) {
    ERR_clear_error();
    const int r = SSL_connect(ssl_);
    if (r == 1) break;
    const int err = SSL_get_error(ssl_, r);
    if (err == SSL_ERROR_WANT_READ || err == SSL_ERROR_WANT_WRITE) {
      if (!waitFd(fd, err == SSL_ERROR_WANT_READ ? POLLIN : POLLOUT, deadline))
        throw fail("TLS handshake timed out after " + seconds(timeout_s) +
                   " s (connect_timeout_s; is this the server's TLS port?)");
      continue;
    }
    const long verify = SSL_get_verify_result(ssl_);
    if (verify != X509_V_OK) {
      std::string why = X509_verify_cert_error_string(verify);
      if (verify == X509_V_ERR_HOSTNAME_MISMATCH || verify == X509_V_ERR_IP_ADDRESS_MISMATCH)
        why += " (the certificate does not name '" + name + "')";
      ERR_clear_error();
      throw fail("server certificate rejected: " + why);
    }
    if (peerClosed(err) || (err == SSL_ERROR_SYSCALL && ERR_peek_error() == 0)) {
      const bool closed =
          err != SSL_ERROR_SYSCALL || r == 0 || errno == 0 || errno == ECONNRESET || errno == EPIPE;
      ERR_clear_error();
      throw fail(closed ? "the server closed the connection during the TLS handshake"
                        : std::string("TLS handshake: ") + std::strerror(errno));
    }
    throw fail("TLS handshake refused: " + opensslErrors());
  }
  if (!context.pins_.empty()) {
    bool pinned = false;
    STACK_OF(X509)* chain = SSL_get0_verified_chain(ssl_);
    for (int i = 0; chain && i < sk_X509_num(chain); ++i) {
      unsigned char md[EVP_MAX_MD_SIZE];
      unsigned int len = 0;
      X509_digest(sk_X509_value(chain, i), EVP_sha256(), md, &len);
      for (const auto& pin : context.pins_)
        pinned |= len == 32 && std::memcmp(md, pin.data(), 32) == 0;
    }
    if (!pinned)
      throw fail(
          "server certificate rejected: no certificate of its verified chain has the "
          "pinned SHA-256 fingerprint (tls_pin_sha256)");
  }
  // TLS 1.3: the server verifies the client certificate after our side of the handshake ended,
  // and answers with session tickets (accepted) or an alert (refused). Wait for that answer.
  if (SSL_version(ssl_) >= TLS1_3_VERSION) {
    char buf[4096];
    while (waitFd(fd, POLLIN, deadline)) {
      ERR_clear_error();
      const int n = SSL_read(ssl_, buf, sizeof buf);
      if (n > 0) {
        early_.append(buf, static_cast<size_t>(n));
        break;
      }
      const int err = SSL_get_error(ssl_, n);
      if (err == SSL_ERROR_WANT_READ) break;  // a session ticket: accepted
      if (err == SSL_ERROR_WANT_WRITE) continue;
      if (peerClosed(err)) {
        ERR_clear_error();
        throw fail(
            "the server closed the connection after the TLS handshake (it refused the "
            "client certificate?)");
      }
      throw fail("TLS handshake refused by the server: " + opensslErrors());
    }
  }
}

TakTlsConnection::~TakTlsConnection() {
  if (ssl_) {
    SSL_shutdown(ssl_);  // non-blocking socket: one attempt
    SSL_free(ssl_);
  }
  ERR_clear_error();
}

bool TakTlsConnection::write(std::string_view data, double timeout_s, std::string& error) {
  size_t done = 0;
  while (done < data.size()) {
    ERR_clear_error();
    const int n = SSL_write(ssl_, data.data() + done, static_cast<int>(data.size() - done));
    if (n > 0) {
      done += static_cast<size_t>(n);
      continue;
    }
    const int err = SSL_get_error(ssl_, n);
    if (err == SSL_ERROR_WANT_WRITE || err == SSL_ERROR_WANT_READ) {
      const auto deadline = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                               std::chrono::duration<double>(timeout_s));
      if (waitFd(fd_, err == SSL_ERROR_WANT_READ ? POLLIN : POLLOUT, deadline)) continue;
      error = "TLS write timed out after " + seconds(timeout_s) + " s";
      return false;
    }
    error = err == SSL_ERROR_SYSCALL && ERR_peek_error() == 0
                ? std::string("TLS write: ") + (errno ? std::strerror(errno) : "connection closed")
                : "TLS write: " + opensslErrors();
    return false;
  }
  return true;
}

bool TakTlsConnection::readAvailable(std::string& out, std::string& error) {
  out += early_;
  early_.clear();
  char buf[16384];
  while (true) {
    pollfd p{fd_, POLLIN, 0};
    if (SSL_pending(ssl_) == 0 && ::poll(&p, 1, 0) <= 0) return true;
    ERR_clear_error();
    const int n = SSL_read(ssl_, buf, sizeof buf);
    if (n > 0) {
      out.append(buf, static_cast<size_t>(n));
      continue;
    }
    const int err = SSL_get_error(ssl_, n);
    if (err == SSL_ERROR_WANT_READ || err == SSL_ERROR_WANT_WRITE) return true;
    if (peerClosed(err)) {
      ERR_clear_error();
      error = "the server closed the TLS connection";
      return false;
    }
    error = "TLS read: " + opensslErrors();
    return false;
  }
}

std::string TakTlsConnection::description() const {
  return std::string(SSL_get_version(ssl_)) + " " + SSL_get_cipher_name(ssl_);
}

}  // namespace hameritt::cop
