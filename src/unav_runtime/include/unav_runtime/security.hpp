// DDS Security the way SROS2 sets it up: a keystore of certificate authorities and enclaves
// (one identity + signed permissions per enclave), governance and permissions documents signed
// as S/MIME, and the ROS 2 environment switches that turn it on for every process:
//
//   ROS_SECURITY_KEYSTORE=DIR ROS_SECURITY_ENABLE=true ROS_SECURITY_STRATEGY=Enforce
//   ROS_SECURITY_ENCLAVE_OVERRIDE=/enclave   (else the node's `--ros-args --enclave`, else "/")
//
// The files and their layout are SROS2's (Humble), so a keystore made by `ros2 security` works
// here and ours works with rmw_fastrtps:
//
//   KEYSTORE/public/{ca,identity_ca,permissions_ca}.cert.pem   KEYSTORE/private/ca.key.pem ...
//   KEYSTORE/enclaves/governance.{xml,p7s}
//   KEYSTORE/enclaves/<enclave>/{cert,key,identity_ca.cert,permissions_ca.cert}.pem,
//                               governance.p7s, permissions.{xml,p7s}
//
// Fast DDS's built-in plugins do the work: PKI-DH authentication (ECDSA P-256 identities),
// Access-Permissions (governance + permissions) and AES-GCM-GMAC encryption. This header has no
// Fast DDS dependency: it makes files and names the participant properties to set.
#pragma once

#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace unav::security {

/// Topic rights of one enclave, as DDS topic names ("rt/rov/thrusters/command"; fnmatch
/// patterns allowed). Deny rules are checked before allow rules; anything unlisted is denied.
struct Permissions {
  std::vector<std::string> allow_publish;
  std::vector<std::string> allow_subscribe;
  std::vector<std::string> deny_publish;
  std::vector<std::string> deny_subscribe;
  /// Every topic, both ways (what `create_enclave` grants, as SROS2 does without a policy).
  static Permissions allow_all();
};

/// Creates KEYSTORE with one self-signed CA (used as identity and permissions CA, as SROS2
/// does) and the signed governance document. Throws ConfigError naming the path when DIR
/// already holds a keystore or cannot be written.
void create_keystore(const std::string& keystore);

/// Creates (or replaces) the enclave's key, certificate (CN=<enclave>, signed by the CA) and
/// signed permissions. `enclave` is an absolute name: "/rov/physics_server".
void create_enclave(const std::string& keystore, const std::string& enclave,
                    const Permissions& permissions = Permissions::allow_all());

/// Rewrites the enclave's permissions (signed) from `permissions`; the identity stays.
void set_permissions(const std::string& keystore, const std::string& enclave, const Permissions& permissions);

/// Reads an SROS2 policy file (<policy version="0.2.0"><enclaves><enclave path=...><profiles>
/// <profile ns= node=><topics publish="ALLOW" subscribe="DENY"><topic>...; <services
/// reply/request=...>) and returns the rights of `enclave`, topic names resolved against the
/// profile's namespace and prefixed as on the wire (rt/, rq/...Request, rr/...Reply).
/// Throws ConfigError naming the file, the element and the rule.
Permissions load_policy(const std::string& policy_file, const std::string& enclave);

/// The enclave paths an SROS2 policy file lists, in file order.
std::vector<std::string> policy_enclaves(const std::string& policy_file);

/// The permissions document (unsigned XML) for an enclave, as SROS2 writes it: a grant for
/// CN=<enclave>, valid 10 years from now, every domain, deny rules then allow rules, and
/// ros_discovery_info allowed both ways (the rmw graph topic every node needs).
std::string permissions_xml(const std::string& enclave, const Permissions& permissions);

/// The governance document (unsigned XML): authenticated participants only, join access
/// control, discovery and liveliness encrypted, RTPS signed, every topic's data and metadata
/// encrypted with read/write access control.
std::string governance_xml();

/// Enclaves of a keystore ("/rov/physics_server"), sorted.
std::vector<std::string> list_enclaves(const std::string& keystore);

/// Checks a signed document against the keystore's permissions CA; returns the signed
/// content. Throws ConfigError if the signature does not verify.
std::string verify_signed(const std::string& keystore, const std::string& p7s_file);

/// Checks that the enclave's certificate was issued by the keystore's identity CA and returns
/// its subject ("CN=/rov/physics_server"). Throws ConfigError otherwise.
std::string verify_identity(const std::string& keystore, const std::string& enclave);

/// The ROS 2 security switches, read from the environment.
struct Environment {
  bool enable = false;            ///< ROS_SECURITY_ENABLE == "true"
  bool enforce = false;           ///< ROS_SECURITY_STRATEGY == "Enforce" (else Permissive)
  std::string keystore;           ///< ROS_SECURITY_KEYSTORE
  std::string enclave_override;   ///< ROS_SECURITY_ENCLAVE_OVERRIDE
  static Environment from_env();  ///< Throws ConfigError on values ROS 2 rejects too.
};

/// Participant properties for `enclave` ("dds.sec.auth.plugin" = "builtin.PKI-DH", the file://
/// URIs of the enclave's files, ...), or nothing when security is off. With Enforce, a missing
/// keystore or enclave file is a ConfigError naming the file and the command that makes it;
/// with Permissive it runs unsecured (and says so through `warning`).
std::optional<std::vector<std::pair<std::string, std::string>>> participant_properties(const Environment& env,
                                                                                       const std::string& enclave,
                                                                                       std::string* warning = nullptr);

}  // namespace unav::security
