#include "unav_runtime/security.hpp"

#include <openssl/bio.h>
#include <openssl/bn.h>
#include <openssl/ec.h>
#include <openssl/err.h>
#include <openssl/evp.h>
#include <openssl/pem.h>
#include <openssl/pkcs7.h>
#include <openssl/x509.h>
#include <openssl/x509v3.h>
#include <tinyxml2.h>

#include <algorithm>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>

#include "unav_common/errors.hpp"

#include <cctype>

namespace fs = std::filesystem;

namespace unav::security {
namespace {

// --- OpenSSL ownership --------------------------------------------------------------------

struct Free {
  void operator()(BIO* p) const { BIO_free_all(p); }
  void operator()(EVP_PKEY* p) const { EVP_PKEY_free(p); }
  void operator()(X509* p) const { X509_free(p); }
  void operator()(X509_STORE* p) const { X509_STORE_free(p); }
  void operator()(X509_STORE_CTX* p) const { X509_STORE_CTX_free(p); }
  void operator()(PKCS7* p) const { PKCS7_free(p); }
  void operator()(BIGNUM* p) const { BN_free(p); }
  void operator()(X509_EXTENSION* p) const { X509_EXTENSION_free(p); }
};
template <class T>
using Owned = std::unique_ptr<T, Free>;

constexpr long kValiditySeconds = 10L * 365 * 24 * 3600;  // SROS2's 10 years
constexpr const char* kCaName = "unav_sim keystore CA";

std::string openssl_error() {
  const unsigned long code = ERR_get_error();
  if (code == 0) return "unknown OpenSSL error";
  char buf[256];
  ERR_error_string_n(code, buf, sizeof(buf));
  ERR_clear_error();
  return buf;
}

[[noreturn]] void fail(const std::string& what) { throw ConfigError(what + ": " + openssl_error()); }

std::string read_text(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw ConfigError(path.string() + ": cannot be read");
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

void write_text(const fs::path& path, const std::string& text, bool secret = false) {
  const fs::path tmp = path.string() + ".tmp";
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out) throw ConfigError(path.string() + ": cannot be written");
    out << text;
    if (!out.flush()) throw ConfigError(path.string() + ": write failed");
  }
  if (secret) fs::permissions(tmp, fs::perms::owner_read | fs::perms::owner_write);
  fs::rename(tmp, path);
}

std::string bio_text(BIO* bio) {
  BUF_MEM* mem = nullptr;
  BIO_get_mem_ptr(bio, &mem);
  return mem ? std::string(mem->data, mem->length) : std::string();
}

Owned<BIO> memory_bio(const std::string& text) {
  Owned<BIO> bio(BIO_new_mem_buf(text.data(), static_cast<int>(text.size())));
  if (!bio) fail("BIO_new_mem_buf");
  return bio;
}

Owned<EVP_PKEY> new_key() {
  Owned<EVP_PKEY> key(EVP_EC_gen("P-256"));  // SROS2's curve (secp256r1), ECDSA-SHA256
  if (!key) fail("generating a P-256 key");
  return key;
}

std::string key_pem(EVP_PKEY* key) {
  Owned<BIO> bio(BIO_new(BIO_s_mem()));
  if (!PEM_write_bio_PrivateKey(bio.get(), key, nullptr, nullptr, 0, nullptr, nullptr)) fail("writing a key");
  return bio_text(bio.get());
}

std::string cert_pem(X509* cert) {
  Owned<BIO> bio(BIO_new(BIO_s_mem()));
  if (!PEM_write_bio_X509(bio.get(), cert)) fail("writing a certificate");
  return bio_text(bio.get());
}

Owned<EVP_PKEY> load_key(const fs::path& path) {
  const std::string text = read_text(path);
  Owned<BIO> bio = memory_bio(text);
  Owned<EVP_PKEY> key(PEM_read_bio_PrivateKey(bio.get(), nullptr, nullptr, nullptr));
  if (!key) fail(path.string() + ": not a PEM private key");
  return key;
}

Owned<X509> load_cert(const fs::path& path) {
  const std::string text = read_text(path);
  Owned<BIO> bio = memory_bio(text);
  Owned<X509> cert(PEM_read_bio_X509(bio.get(), nullptr, nullptr, nullptr));
  if (!cert) fail(path.string() + ": not a PEM certificate");
  return cert;
}

void add_extension(X509* cert, X509* issuer, int nid, const char* value) {
  X509V3_CTX ctx;
  X509V3_set_ctx(&ctx, issuer, cert, nullptr, nullptr, 0);
  Owned<X509_EXTENSION> ext(X509V3_EXT_conf_nid(nullptr, &ctx, nid, value));
  if (!ext || !X509_add_ext(cert, ext.get(), -1)) fail(std::string("certificate extension ") + value);
}

/// A certificate for `key` with subject CN=`common_name`, signed by (issuer, issuer_key), or
/// self-signed when issuer is null.
Owned<X509> make_cert(EVP_PKEY* key, const std::string& common_name, X509* issuer, EVP_PKEY* issuer_key) {
  Owned<X509> cert(X509_new());
  if (!cert) fail("X509_new");
  X509_set_version(cert.get(), 2);  // v3
  Owned<BIGNUM> serial(BN_new());
  if (!serial || !BN_rand(serial.get(), 64, BN_RAND_TOP_ANY, BN_RAND_BOTTOM_ANY) ||
      !BN_to_ASN1_INTEGER(serial.get(), X509_get_serialNumber(cert.get())))
    fail("certificate serial number");
  X509_gmtime_adj(X509_getm_notBefore(cert.get()), 0);
  X509_gmtime_adj(X509_getm_notAfter(cert.get()), kValiditySeconds);
  X509_set_pubkey(cert.get(), key);
  X509_NAME* subject = X509_get_subject_name(cert.get());
  if (!X509_NAME_add_entry_by_txt(subject, "CN", MBSTRING_UTF8,
                                  reinterpret_cast<const unsigned char*>(common_name.c_str()), -1, -1, 0))
    fail("certificate subject CN=" + common_name);
  X509* signer = issuer ? issuer : cert.get();
  X509_set_issuer_name(cert.get(), X509_get_subject_name(signer));
  if (issuer) {
    add_extension(cert.get(), signer, NID_basic_constraints, "critical,CA:FALSE");
    add_extension(cert.get(), signer, NID_key_usage, "critical,digitalSignature,keyAgreement");
  } else {
    add_extension(cert.get(), signer, NID_basic_constraints, "critical,CA:TRUE,pathlen:1");
    add_extension(cert.get(), signer, NID_key_usage, "critical,keyCertSign,cRLSign,digitalSignature");
  }
  add_extension(cert.get(), signer, NID_subject_key_identifier, "hash");
  if (!X509_sign(cert.get(), issuer_key ? issuer_key : key, EVP_sha256())) fail("signing the certificate");
  return cert;
}

/// S/MIME (detached, text) signature of `text`, as SROS2 signs governance and permissions.
std::string smime_sign(const std::string& text, X509* cert, EVP_PKEY* key) {
  const int flags = PKCS7_DETACHED | PKCS7_TEXT;
  Owned<BIO> in = memory_bio(text);
  Owned<PKCS7> p7(PKCS7_sign(cert, key, nullptr, in.get(), flags));
  if (!p7) fail("signing a document");
  Owned<BIO> again = memory_bio(text);
  Owned<BIO> out(BIO_new(BIO_s_mem()));
  if (!SMIME_write_PKCS7(out.get(), p7.get(), again.get(), flags)) fail("writing an S/MIME document");
  return bio_text(out.get());
}

// --- keystore layout ------------------------------------------------------------------------

fs::path enclaves_dir(const std::string& keystore) { return fs::path(keystore) / "enclaves"; }

void check_enclave_name(const std::string& enclave) {
  const bool ok = !enclave.empty() && enclave.front() == '/' && (enclave.size() == 1 || enclave.back() != '/') &&
                  enclave.find("//") == std::string::npos && std::all_of(enclave.begin(), enclave.end(), [](char c) {
                    return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '/';
                  });
  if (!ok)
    throw ConfigError("enclave '" + enclave +
                      "': expected an absolute name of letters, digits and '_' separated by '/', e.g. "
                      "/rov/physics_server");
}

fs::path enclave_dir(const std::string& keystore, const std::string& enclave) {
  check_enclave_name(enclave);
  return enclave == "/" ? enclaves_dir(keystore) : enclaves_dir(keystore) / enclave.substr(1);
}

void require_keystore(const std::string& keystore) {
  for (const char* f : {"public/ca.cert.pem", "private/ca.key.pem", "enclaves/governance.p7s"})
    if (!fs::exists(fs::path(keystore) / f))
      throw ConfigError("keystore '" + keystore + "': missing " + f +
                        " (create one with `unav security create_keystore " + keystore + "`)");
}

void relative_link(const fs::path& target, const fs::path& link) {
  std::error_code ec;
  fs::remove(link, ec);
  fs::create_symlink(fs::relative(target, link.parent_path()), link);
}

std::string utc(std::time_t t) {
  std::tm tm{};
  gmtime_r(&t, &tm);
  char buf[32];
  std::strftime(buf, sizeof(buf), "%Y-%m-%dT%H:%M:%S", &tm);
  return buf;
}

std::string xml_escape(const std::string& s) {
  std::string out;
  for (char c : s) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

void topics_block(std::ostringstream& x, const char* kind, const std::vector<std::string>& topics) {
  if (topics.empty()) return;
  x << "        <" << kind << ">\n          <topics>\n";
  for (const auto& t : topics) x << "            <topic>" << xml_escape(t) << "</topic>\n";
  x << "          </topics>\n        </" << kind << ">\n";
}

void rule(std::ostringstream& x, const char* kind, const std::vector<std::string>& pub,
          const std::vector<std::string>& sub) {
  if (pub.empty() && sub.empty()) return;
  x << "      <" << kind << ">\n"
    << "        <domains>\n          <id_range>\n            <min>0</min>\n            <max>232</max>\n"
    << "          </id_range>\n        </domains>\n";
  topics_block(x, "publish", pub);
  topics_block(x, "subscribe", sub);
  x << "      </" << kind << ">\n";
}

void sign_permissions(const std::string& keystore, const std::string& enclave, const Permissions& permissions) {
  const fs::path dir = enclave_dir(keystore, enclave);
  const std::string xml = permissions_xml(enclave, permissions);
  Owned<X509> ca = load_cert(fs::path(keystore) / "public/permissions_ca.cert.pem");
  Owned<EVP_PKEY> ca_key = load_key(fs::path(keystore) / "private/permissions_ca.key.pem");
  write_text(dir / "permissions.xml", xml);
  write_text(dir / "permissions.p7s", smime_sign(xml, ca.get(), ca_key.get()));
}

// --- SROS2 policy -------------------------------------------------------------------------

std::string fully_qualified(const std::string& name, const std::string& ns, const std::string& node) {
  std::string n = name;
  if (n == "~" || n.rfind("~/", 0) == 0) n = (ns == "/" ? "" : ns) + "/" + node + n.substr(1);  // private
  if (n.empty() || n.front() != '/') n = (ns == "/" ? "" : ns) + "/" + n;
  return n;
}

}  // namespace

Permissions Permissions::allow_all() {
  Permissions p;
  p.allow_publish = {"*"};
  p.allow_subscribe = {"*"};
  return p;
}

std::string governance_xml() {
  return R"(<?xml version="1.0" encoding="UTF-8"?>
<dds xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance" xsi:noNamespaceSchemaLocation="http://www.omg.org/spec/DDS-SECURITY/20170901/omg_shared_ca_governance.xsd">
  <domain_access_rules>
    <domain_rule>
      <domains>
        <id_range>
          <min>0</min>
          <max>232</max>
        </id_range>
      </domains>
      <allow_unauthenticated_participants>false</allow_unauthenticated_participants>
      <enable_join_access_control>true</enable_join_access_control>
      <discovery_protection_kind>ENCRYPT</discovery_protection_kind>
      <liveliness_protection_kind>ENCRYPT</liveliness_protection_kind>
      <rtps_protection_kind>SIGN</rtps_protection_kind>
      <topic_access_rules>
        <topic_rule>
          <topic_expression>*</topic_expression>
          <enable_discovery_protection>true</enable_discovery_protection>
          <enable_liveliness_protection>true</enable_liveliness_protection>
          <enable_read_access_control>true</enable_read_access_control>
          <enable_write_access_control>true</enable_write_access_control>
          <metadata_protection_kind>ENCRYPT</metadata_protection_kind>
          <data_protection_kind>ENCRYPT</data_protection_kind>
        </topic_rule>
      </topic_access_rules>
    </domain_rule>
  </domain_access_rules>
</dds>
)";
}

std::string permissions_xml(const std::string& enclave, const Permissions& permissions) {
  check_enclave_name(enclave);
  const std::time_t now = std::time(nullptr);
  std::ostringstream x;
  x << R"(<?xml version="1.0" encoding="UTF-8"?>
<dds xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance" xsi:noNamespaceSchemaLocation="http://www.omg.org/spec/DDS-SECURITY/20170901/omg_shared_ca_permissions.xsd">
  <permissions>
)";
  x << "    <grant name=\"" << xml_escape(enclave) << "\">\n"
    << "      <subject_name>CN=" << xml_escape(enclave) << "</subject_name>\n"
    << "      <validity>\n        <not_before>" << utc(now - 60) << "</not_before>\n"
    << "        <not_after>" << utc(now + kValiditySeconds) << "</not_after>\n      </validity>\n";
  rule(x, "deny_rule", permissions.deny_publish, permissions.deny_subscribe);
  rule(x, "allow_rule", {"ros_discovery_info"}, {"ros_discovery_info"});
  rule(x, "allow_rule", permissions.allow_publish, permissions.allow_subscribe);
  x << "      <default>DENY</default>\n    </grant>\n  </permissions>\n</dds>\n";
  return x.str();
}

void create_keystore(const std::string& keystore) {
  const fs::path root(keystore);
  if (fs::exists(root / "public/ca.cert.pem"))
    throw ConfigError("keystore '" + keystore + "' already exists (public/ca.cert.pem is there)");
  std::error_code ec;
  for (const char* sub : {"public", "private", "enclaves"}) {
    fs::create_directories(root / sub, ec);
    if (ec) throw ConfigError("keystore '" + keystore + "': cannot create " + sub + ": " + ec.message());
  }
  fs::permissions(root / "private", fs::perms::owner_all, ec);
  Owned<EVP_PKEY> key = new_key();
  Owned<X509> ca = make_cert(key.get(), kCaName, nullptr, nullptr);
  write_text(root / "private/ca.key.pem", key_pem(key.get()), /*secret=*/true);
  write_text(root / "public/ca.cert.pem", cert_pem(ca.get()));
  for (const char* role : {"identity_ca", "permissions_ca"}) {
    relative_link(root / "public/ca.cert.pem", root / "public" / (std::string(role) + ".cert.pem"));
    relative_link(root / "private/ca.key.pem", root / "private" / (std::string(role) + ".key.pem"));
  }
  const std::string governance = governance_xml();
  write_text(root / "enclaves/governance.xml", governance);
  write_text(root / "enclaves/governance.p7s", smime_sign(governance, ca.get(), key.get()));
}

void create_enclave(const std::string& keystore, const std::string& enclave, const Permissions& permissions) {
  require_keystore(keystore);
  const fs::path dir = enclave_dir(keystore, enclave);
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) throw ConfigError("enclave '" + enclave + "': cannot create " + dir.string() + ": " + ec.message());
  const fs::path root(keystore);
  Owned<X509> ca = load_cert(root / "public/identity_ca.cert.pem");
  Owned<EVP_PKEY> ca_key = load_key(root / "private/identity_ca.key.pem");
  Owned<EVP_PKEY> key = new_key();
  Owned<X509> cert = make_cert(key.get(), enclave, ca.get(), ca_key.get());
  write_text(dir / "key.pem", key_pem(key.get()), /*secret=*/true);
  write_text(dir / "cert.pem", cert_pem(cert.get()));
  relative_link(root / "public/identity_ca.cert.pem", dir / "identity_ca.cert.pem");
  relative_link(root / "public/permissions_ca.cert.pem", dir / "permissions_ca.cert.pem");
  if (enclave != "/") relative_link(enclaves_dir(keystore) / "governance.p7s", dir / "governance.p7s");
  sign_permissions(keystore, enclave, permissions);
}

void set_permissions(const std::string& keystore, const std::string& enclave, const Permissions& permissions) {
  require_keystore(keystore);
  if (!fs::exists(enclave_dir(keystore, enclave) / "cert.pem"))
    throw ConfigError("enclave '" + enclave + "' is not in keystore '" + keystore +
                      "' (create it with `unav security create_enclave " + keystore + " " + enclave + "`)");
  sign_permissions(keystore, enclave, permissions);
}

std::vector<std::string> list_enclaves(const std::string& keystore) {
  std::vector<std::string> out;
  const fs::path root = enclaves_dir(keystore);
  if (!fs::is_directory(root)) throw ConfigError("keystore '" + keystore + "': no enclaves/ directory");
  for (const auto& entry : fs::recursive_directory_iterator(root)) {
    if (entry.path().filename() != "cert.pem") continue;
    const std::string rel = fs::relative(entry.path().parent_path(), root).generic_string();
    out.push_back(rel == "." ? "/" : "/" + rel);
  }
  std::sort(out.begin(), out.end());
  return out;
}

std::string verify_signed(const std::string& keystore, const std::string& p7s_file) {
  const std::string text = read_text(p7s_file);
  Owned<BIO> in = memory_bio(text);
  BIO* content_raw = nullptr;
  Owned<PKCS7> p7(SMIME_read_PKCS7(in.get(), &content_raw));
  Owned<BIO> content(content_raw);
  if (!p7) fail(p7s_file + ": not an S/MIME document");
  Owned<X509> ca = load_cert(fs::path(keystore) / "public/permissions_ca.cert.pem");
  Owned<X509_STORE> store(X509_STORE_new());
  X509_STORE_add_cert(store.get(), ca.get());
  Owned<BIO> out(BIO_new(BIO_s_mem()));
  if (PKCS7_verify(p7.get(), nullptr, store.get(), content.get(), out.get(), PKCS7_TEXT) != 1)
    fail(p7s_file + ": signature does not verify against " + keystore + "/public/permissions_ca.cert.pem");
  // S/MIME text mode signs the canonical form (CRLF line ends): give the document back as written.
  std::string signed_text = bio_text(out.get());
  std::string text_out;
  text_out.reserve(signed_text.size());
  for (size_t i = 0; i < signed_text.size(); ++i)
    if (!(signed_text[i] == '\r' && i + 1 < signed_text.size() && signed_text[i + 1] == '\n'))
      text_out += signed_text[i];
  return text_out;
}

std::string verify_identity(const std::string& keystore, const std::string& enclave) {
  const fs::path dir = enclave_dir(keystore, enclave);
  Owned<X509> ca = load_cert(fs::path(keystore) / "public/identity_ca.cert.pem");
  Owned<X509> cert = load_cert(dir / "cert.pem");
  Owned<X509_STORE> store(X509_STORE_new());
  X509_STORE_add_cert(store.get(), ca.get());
  Owned<X509_STORE_CTX> ctx(X509_STORE_CTX_new());
  X509_STORE_CTX_init(ctx.get(), store.get(), cert.get(), nullptr);
  if (X509_verify_cert(ctx.get()) != 1)
    throw ConfigError((dir / "cert.pem").string() + ": not issued by the keystore's identity CA (" +
                      X509_verify_cert_error_string(X509_STORE_CTX_get_error(ctx.get())) + ")");
  Owned<BIO> out(BIO_new(BIO_s_mem()));
  X509_NAME_print_ex(out.get(), X509_get_subject_name(cert.get()), 0, XN_FLAG_RFC2253 & ~ASN1_STRFLGS_ESC_MSB);
  return bio_text(out.get());
}

namespace {

const tinyxml2::XMLElement* policy_enclaves_element(tinyxml2::XMLDocument& doc, const std::string& policy_file) {
  if (doc.LoadFile(policy_file.c_str()) != tinyxml2::XML_SUCCESS)
    throw ConfigError(policy_file + ": not a readable XML file (" + doc.ErrorStr() + ")");
  const tinyxml2::XMLElement* policy = doc.FirstChildElement("policy");
  if (!policy) throw ConfigError(policy_file + ": the root element must be <policy>");
  const tinyxml2::XMLElement* enclaves = policy->FirstChildElement("enclaves");
  if (!enclaves) throw ConfigError(policy_file + ": <policy> has no <enclaves>");
  return enclaves;
}

}  // namespace

std::vector<std::string> policy_enclaves(const std::string& policy_file) {
  tinyxml2::XMLDocument doc;
  const tinyxml2::XMLElement* enclaves = policy_enclaves_element(doc, policy_file);
  std::vector<std::string> out;
  for (const auto* e = enclaves->FirstChildElement("enclave"); e; e = e->NextSiblingElement("enclave")) {
    const char* path = e->Attribute("path");
    if (!path) throw ConfigError(policy_file + ":" + std::to_string(e->GetLineNum()) + ": <enclave> needs path=");
    check_enclave_name(path);
    out.emplace_back(path);
  }
  return out;
}

Permissions load_policy(const std::string& policy_file, const std::string& enclave) {
  tinyxml2::XMLDocument doc;
  const tinyxml2::XMLElement* enclaves = policy_enclaves_element(doc, policy_file);
  Permissions out;
  struct Way {
    const char* attribute;
    std::vector<std::string>* allow;
    std::vector<std::string>* deny;
    const char* prefix;
    const char* suffix;
  };
  const std::vector<Way> topic_ways = {{"publish", &out.allow_publish, &out.deny_publish, "rt", ""},
                                       {"subscribe", &out.allow_subscribe, &out.deny_subscribe, "rt", ""}};
  // A service server reads requests and writes replies; a client the reverse.
  const std::vector<Way> service_ways = {{"reply", &out.allow_subscribe, &out.deny_subscribe, "rq", "Request"},
                                         {"reply", &out.allow_publish, &out.deny_publish, "rr", "Reply"},
                                         {"request", &out.allow_publish, &out.deny_publish, "rq", "Request"},
                                         {"request", &out.allow_subscribe, &out.deny_subscribe, "rr", "Reply"}};
  bool found = false;
  for (const auto* e = enclaves->FirstChildElement("enclave"); e; e = e->NextSiblingElement("enclave")) {
    const char* path = e->Attribute("path");
    if (!path) throw ConfigError(policy_file + ":" + std::to_string(e->GetLineNum()) + ": <enclave> needs path=");
    if (enclave != path) continue;
    found = true;
    const auto* profiles = e->FirstChildElement("profiles");
    for (const auto* p = profiles ? profiles->FirstChildElement() : nullptr; p; p = p->NextSiblingElement()) {
      const std::string where = policy_file + ":" + std::to_string(p->GetLineNum()) + ": ";
      if (std::string(p->Name()) != "profile") throw ConfigError(where + "<" + p->Name() + "> inside <profiles>");
      const char* ns = p->Attribute("ns");
      const char* node = p->Attribute("node");
      if (!ns || !node || ns[0] != '/') throw ConfigError(where + "<profile> needs ns=\"/...\" and node=\"...\"");
      for (const auto* g = p->FirstChildElement(); g; g = g->NextSiblingElement()) {
        const std::string group = g->Name();
        const std::string at = policy_file + ":" + std::to_string(g->GetLineNum()) + ": ";
        const char* item = nullptr;
        const std::vector<Way>* ways = nullptr;
        if (group == "topics") {
          item = "topic";
          ways = &topic_ways;
        } else if (group == "services") {
          item = "service";
          ways = &service_ways;
        } else {
          throw ConfigError(at + "<" + group + ">: supported are <topics> and <services> (actions and " +
                            "XInclude are not; list their topics)");
        }
        for (const auto& way : *ways) {
          const char* value = g->Attribute(way.attribute);
          if (!value) continue;
          const std::string v = value;
          if (v != "ALLOW" && v != "DENY")
            throw ConfigError(at + "<" + group + "> " + way.attribute + "=\"" + v + "\": expected ALLOW or DENY");
          for (const auto* t = g->FirstChildElement(item); t; t = t->NextSiblingElement(item)) {
            const char* text = t->GetText();
            if (!text || !*text) throw ConfigError(at + "empty <" + item + ">");
            std::string name = way.prefix + fully_qualified(text, ns, node) + way.suffix;
            (v == "ALLOW" ? way.allow : way.deny)->push_back(std::move(name));
          }
        }
      }
    }
  }
  if (!found) throw ConfigError(policy_file + ": no <enclave path=\"" + enclave + "\">");
  return out;
}

Environment Environment::from_env() {
  auto get = [](const char* name) -> std::string {
    const char* v = std::getenv(name);
    return v ? v : "";
  };
  Environment env;
  env.enable = get("ROS_SECURITY_ENABLE") == "true";
  const std::string strategy = get("ROS_SECURITY_STRATEGY");
  env.enforce = strategy == "Enforce";
  if (!strategy.empty() && strategy != "Enforce" && strategy != "Permissive")
    throw ConfigError("environment ROS_SECURITY_STRATEGY='" + strategy + "': expected Enforce or Permissive");
  env.keystore = get("ROS_SECURITY_KEYSTORE");
  env.enclave_override = get("ROS_SECURITY_ENCLAVE_OVERRIDE");
  return env;
}

std::optional<std::vector<std::pair<std::string, std::string>>> participant_properties(const Environment& env,
                                                                                       const std::string& enclave,
                                                                                       std::string* warning) {
  if (!env.enable) return std::nullopt;
  const std::string name = env.enclave_override.empty() ? (enclave.empty() ? "/" : enclave) : env.enclave_override;
  auto missing = [&](const std::string& what) -> std::optional<std::vector<std::pair<std::string, std::string>>> {
    if (env.enforce) throw ConfigError("ROS_SECURITY_STRATEGY=Enforce: " + what);
    if (warning) *warning = "security is enabled but " + what + "; running WITHOUT security (Permissive)";
    return std::nullopt;
  };
  if (env.keystore.empty()) return missing("ROS_SECURITY_KEYSTORE is not set");
  if (!fs::is_directory(env.keystore)) return missing("keystore '" + env.keystore + "' is not a directory");
  check_enclave_name(name);
  const fs::path dir = fs::absolute(enclave_dir(env.keystore, name));
  for (const char* f : {"identity_ca.cert.pem", "cert.pem", "key.pem", "permissions_ca.cert.pem", "governance.p7s",
                        "permissions.p7s"}) {
    if (!fs::exists(dir / f))
      return missing("enclave '" + name + "' has no " + (dir / f).string() + " (create it with `unav security " +
                     "create_enclave " + env.keystore + " " + name + "`)");
  }
  auto uri = [&](const char* f) { return "file://" + fs::canonical(dir / f).string(); };
  std::vector<std::pair<std::string, std::string>> props = {
      {"dds.sec.auth.plugin", "builtin.PKI-DH"},
      {"dds.sec.auth.builtin.PKI-DH.identity_ca", uri("identity_ca.cert.pem")},
      {"dds.sec.auth.builtin.PKI-DH.identity_certificate", uri("cert.pem")},
      {"dds.sec.auth.builtin.PKI-DH.private_key", uri("key.pem")},
      {"dds.sec.access.plugin", "builtin.Access-Permissions"},
      {"dds.sec.access.builtin.Access-Permissions.permissions_ca", uri("permissions_ca.cert.pem")},
      {"dds.sec.access.builtin.Access-Permissions.governance", uri("governance.p7s")},
      {"dds.sec.access.builtin.Access-Permissions.permissions", uri("permissions.p7s")},
      {"dds.sec.crypto.plugin", "builtin.AES-GCM-GMAC"},
  };
  if (fs::exists(dir / "crl.pem")) props.emplace_back("dds.sec.auth.builtin.PKI-DH.identity_crl", uri("crl.pem"));
  return props;
}

}  // namespace unav::security
