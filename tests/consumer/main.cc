// A minimal program built against the installed telegrasp package: a bad option is rejected,
// then a client on the DDS domain given as the argument publishes one sample. The library finds
// its Fast DDS profiles in the installed prefix by itself.
//   telegrasp-consumer DOMAIN      (a domain nobody else uses; the test leases one)
#include <telegrasp/client/client.h>

#include <iostream>
#include <stdexcept>
#include <string>

int main(int argc, char** argv) {
  using namespace telegrasp::client;
  if (argc != 2) {
    std::cerr << "usage: telegrasp-consumer DOMAIN\n";
    return 2;
  }

  ClientOptions bad;
  bad.client_id = "";
  try {
    Client client(bad);
    std::cerr << "an empty client id was accepted\n";
    return 1;
  } catch (const std::runtime_error& e) {
    std::cout << "rejected as expected: " << e.what() << "\n";
  }

  ClientOptions options;
  options.client_id = "consumer";
  options.domain = std::stoi(argv[1]);  // private: nobody else is here
  options.topics = kServerStatuses;
  Client client(options);
  ControllerSample sample;
  sample.side = HandSide::kLeft;
  sample.X_WorldPalm.translation() = Eigen::Vector3d(0.1, -0.3, 0.9);
  const std::uint64_t sequence = client.publish(sample);
  std::cout << "published sample " << sequence << " of " << client.client_id() << "'s " << to_string(sample.side)
            << " hand; server found: " << std::boolalpha << client.wait_for_server(std::chrono::milliseconds(20))
            << "\n";
  return sequence == 1 ? 0 : 1;
}
