#include "security_command.hpp"

#include <filesystem>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include "unav_runtime/security.hpp"

namespace unav::cli {

namespace {

struct SecurityArgs {
  std::string keystore;
  std::string enclave;
  std::string policy;
  std::vector<std::string> enclaves;
  std::vector<std::string> policies;
};

}  // namespace

std::function<int()> add_security_command(CLI::App& app) {
  auto args = std::make_shared<SecurityArgs>();
  auto* sec = app.add_subcommand("security", "DDS Security keystores, as `ros2 security` makes them");
  sec->require_subcommand(1);
  auto* keystore = sec->add_subcommand("create_keystore", "create a keystore: a CA and the signed governance");
  keystore->add_option("ROOT", args->keystore, "keystore directory")->required();
  auto* enclave = sec->add_subcommand("create_enclave",
                                      "create an enclave: its key, certificate and permissions "
                                      "(every topic; narrow them with create_permission)");
  enclave->add_option("ROOT", args->keystore, "keystore directory")->required();
  enclave->add_option("NAME", args->enclave, "enclave, e.g. /rov/physics_server")->required();
  auto* permission = sec->add_subcommand("create_permission", "sign an enclave's permissions from an SROS2 policy");
  permission->add_option("ROOT", args->keystore, "keystore directory")->required();
  permission->add_option("NAME", args->enclave, "enclave")->required();
  permission->add_option("POLICY_FILE_PATH", args->policy, "SROS2 policy XML")->required()->check(CLI::ExistingFile);
  auto* list = sec->add_subcommand("list_enclaves", "list the enclaves of a keystore");
  list->add_option("ROOT", args->keystore, "keystore directory")->required();
  auto* generate =
      sec->add_subcommand("generate_artifacts", "create the keystore if needed, and enclaves with or without a policy");
  generate->add_option("-k,--keystore-root-path", args->keystore, "keystore directory")->required();
  generate->add_option("-e,--enclaves", args->enclaves, "enclaves with every topic allowed");
  generate->add_option("-p,--policy-files", args->policies, "SROS2 policy files: every enclave they list")
      ->check(CLI::ExistingFile);

  return [=]() -> int {
    namespace s = unav::security;
    if (keystore->parsed()) {
      s::create_keystore(args->keystore);
      std::cout << "created keystore " << args->keystore << "\n";
    } else if (enclave->parsed()) {
      s::create_enclave(args->keystore, args->enclave);
      std::cout << "created enclave " << args->enclave << " in " << args->keystore << "\n";
    } else if (permission->parsed()) {
      s::set_permissions(args->keystore, args->enclave, s::load_policy(args->policy, args->enclave));
      std::cout << "signed permissions of " << args->enclave << " from " << args->policy << "\n";
    } else if (list->parsed()) {
      for (const auto& e : s::list_enclaves(args->keystore)) std::cout << e << "\n";
    } else if (generate->parsed()) {
      if (!std::filesystem::exists(std::filesystem::path(args->keystore) / "public/ca.cert.pem")) {
        s::create_keystore(args->keystore);
        std::cout << "created keystore " << args->keystore << "\n";
      }
      for (const auto& e : args->enclaves) {
        s::create_enclave(args->keystore, e);
        std::cout << "created enclave " << e << "\n";
      }
      for (const auto& p : args->policies) {
        for (const auto& e : s::policy_enclaves(p)) {
          s::create_enclave(args->keystore, e, s::load_policy(p, e));
          std::cout << "created enclave " << e << " with the permissions of " << p << "\n";
        }
      }
    }
    return 0;
  };
}

}  // namespace unav::cli
