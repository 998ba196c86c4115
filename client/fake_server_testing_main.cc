// geodex-fake-server: the in-process test fake (fake_geodex_service_testing.h) as a
// process, for testing the CLI without server/. Same flags as geodex-server;
// --models is accepted and ignored (the fake serves model "fake").
//
//   geodex-fake-server --listen 127.0.0.1:PORT [--models DIR]

#include <csignal>
#include <cstdio>
#include <string>

#include "CLI/CLI.hpp"
#include "client/fake_geodex_service_testing.h"
#include "grpcpp/grpcpp.h"

int main(int argc, char** argv) {
  std::string listen = "127.0.0.1:50051", models;
  CLI::App app{"geodex-fake-server: a fake geodex server for client tests."};
  app.add_option("--listen", listen, "Address to listen on")->capture_default_str();
  app.add_option("--models", models, "Ignored");
  CLI11_PARSE(app, argc, argv);
  geodex::client::testing::FakeGeodexService service;
  grpc::ServerBuilder builder;
  int port = 0;
  builder.AddListeningPort(listen, grpc::InsecureServerCredentials(), &port);
  builder.RegisterService(&service);
  std::unique_ptr<grpc::Server> server = builder.BuildAndStart();
  if (server == nullptr || port == 0) {
    std::fprintf(stderr, "geodex-fake-server: cannot listen on %s\n", listen.c_str());
    return 1;
  }
  std::fprintf(stderr, "geodex-fake-server: listening on port %d\n", port);
  server->Wait();  // until killed
  return 0;
}
