#pragma once

// DDS domains for tests. Fast DDS's shared-memory transport is not separated by network
// namespaces, so two test processes running at once must never share a domain: each domain is
// reserved with an exclusive lock file for as long as the process lives.

namespace teejet::testing {

// The domain of this test process (reserved on first use; the same on every call).
int test_domain();

// One more domain of this process's own, different from every other reserved one (a domain
// where no gateway runs, a second gateway's, ...).
int another_test_domain();

}  // namespace teejet::testing
