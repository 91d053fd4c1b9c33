// A module for the loader's tests (module_test.cpp): it says it was built for ABI "test-abi"
// and exports one function.

extern "C" __attribute__((visibility("default"))) const char* csgtile_module_abi() {
  return "test-abi";
}

extern "C" __attribute__((visibility("default"))) int csgtile_test_answer() { return 42; }
