// Linked into a test program that runs several DDS participants in one process (an observer and
// clients, or a raw participant and a Client): turns Fast DDS intraprocess delivery off before
// main(), so that their samples go through shared memory as between processes. With intraprocess
// delivery, Fast DDS 2.9.1 can deadlock two participants of one process in the Writer Liveliness
// Protocol (eProsima/Fast-DDS#3115; see tests/bench/net/bench_common.h): the test stops receiving
// and then hangs in teardown until ctest's timeout.
#include <fastrtps/attributes/LibrarySettingsAttributes.h>
#include <fastrtps/xmlparser/XMLProfileManager.h>

namespace {

const bool intraprocess_off = [] {
  eprosima::fastrtps::LibrarySettingsAttributes settings;
  settings.intraprocess_delivery = eprosima::fastrtps::INTRAPROCESS_OFF;
  eprosima::fastrtps::xmlparser::XMLProfileManager::library_settings(settings);
  return true;
}();

}  // namespace
