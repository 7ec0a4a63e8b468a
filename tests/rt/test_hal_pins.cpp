// Pin, parameter and signal semantics of the HAL, as LinuxCNC defines them.
#include <gtest/gtest.h>

#include "truecut/rt/hal.hpp"

using namespace truecut::rt::hal;

namespace {

// A component made directly through the C ABI, the way a plugin makes one.
struct Fixture {
  double* f_in = nullptr;
  double* f_out = nullptr;
  double* f_out2 = nullptr;
  double* f_io = nullptr;
  bool* b_in = nullptr;
  int32_t* s_in = nullptr;
  uint32_t* u_out = nullptr;
  double gain_param = 2.0;
  int32_t ro_param = 7;
};

Fixture* g_fix = nullptr;

int fixture_init(const tc_hal_api_t* api, tc_hal_t* hal, int, const char* const*, void**) {
  Fixture& f = *g_fix;
  int id = api->component_new(hal, "fx");
  if (id <= 0) return id;
  int rc = 0;
  rc |= api->pin_new(hal, id, "fx.f-in", TC_HAL_FLOAT, TC_HAL_IN, (void**)&f.f_in);
  rc |= api->pin_new(hal, id, "fx.f-out", TC_HAL_FLOAT, TC_HAL_OUT, (void**)&f.f_out);
  rc |= api->pin_new(hal, id, "fx.f-out2", TC_HAL_FLOAT, TC_HAL_OUT, (void**)&f.f_out2);
  rc |= api->pin_new(hal, id, "fx.f-io", TC_HAL_FLOAT, TC_HAL_IO, (void**)&f.f_io);
  rc |= api->pin_new(hal, id, "fx.b-in", TC_HAL_BIT, TC_HAL_IN, (void**)&f.b_in);
  rc |= api->pin_new(hal, id, "fx.s-in", TC_HAL_S32, TC_HAL_IN, (void**)&f.s_in);
  rc |= api->pin_new(hal, id, "fx.u-out", TC_HAL_U32, TC_HAL_OUT, (void**)&f.u_out);
  rc |= api->param_new(hal, id, "fx.gain", TC_HAL_FLOAT, TC_HAL_RW, &f.gain_param);
  rc |= api->param_new(hal, id, "fx.ro", TC_HAL_S32, TC_HAL_RO, &f.ro_param);
  if (rc) return -22;
  return api->component_ready(hal, id);
}
void fixture_exit(const tc_hal_api_t*, tc_hal_t*, void*) {}

class HalPins : public ::testing::Test {
 protected:
  void SetUp() override {
    g_fix = &fix;
    hal.load("fx", fixture_init, fixture_exit);
  }
  Fixture fix;
  Hal hal;
};

}  // namespace

TEST_F(HalPins, UnlinkedPinReadsItsOwnValueAndSetpChangesIt) {
  EXPECT_EQ(0.0, *fix.f_in);
  hal.set_pin_or_param("fx.f-in", "1.25");
  EXPECT_EQ(1.25, *fix.f_in);
  EXPECT_EQ(1.25, hal.get_pin_or_param("fx.f-in").f);
}

TEST_F(HalPins, LinkedPinsShareTheSignalValue) {
  hal.link("fx.f-out", "sig");
  hal.link("fx.f-in", "sig");
  *fix.f_out = 3.5;
  EXPECT_EQ(3.5, *fix.f_in);
  EXPECT_EQ(3.5, hal.get_signal("sig").f);
  EXPECT_EQ(fix.f_in, fix.f_out) << "both pins point at the signal's storage";
}

TEST_F(HalPins, FirstPinGivesTheNewSignalItsValue) {
  hal.set_pin_or_param("fx.f-in", "4.5");
  hal.link("fx.f-in", "s");
  EXPECT_EQ(4.5, hal.get_signal("s").f);
}

TEST_F(HalPins, UnlinkedPinKeepsTheLastSignalValue) {
  hal.link("fx.f-out", "sig");
  hal.link("fx.f-in", "sig");
  *fix.f_out = 9.0;
  hal.unlink("fx.f-in");
  *fix.f_out = 1.0;
  EXPECT_EQ(9.0, *fix.f_in);
  EXPECT_EQ(1.0, hal.get_signal("sig").f);
}

TEST_F(HalPins, TwoWritersOnOneSignalAreRefused) {
  hal.link("fx.f-out", "sig");
  try {
    hal.link("fx.f-out2", "sig");
    FAIL() << "second writer accepted";
  } catch (const HalError& e) {
    EXPECT_NE(std::string(e.what()).find("already has a writer (fx.f-out)"), std::string::npos)
        << e.what();
  }
}

TEST_F(HalPins, IoPinCannotJoinASignalWithAWriterNorTheReverse) {
  hal.link("fx.f-out", "a");
  EXPECT_THROW(hal.link("fx.f-io", "a"), HalError);
  hal.link("fx.f-io", "b");
  EXPECT_THROW(hal.link("fx.f-out", "b"), HalError);  // f-out is on 'a' anyway
  EXPECT_THROW(hal.link("fx.f-out2", "b"), HalError);
}

TEST_F(HalPins, TypeMismatchIsRefused) {
  hal.link("fx.f-out", "sig");
  try {
    hal.link("fx.b-in", "sig");
    FAIL();
  } catch (const HalError& e) {
    EXPECT_STREQ("type mismatch: pin 'fx.b-in' is bit, signal 'sig' is float", e.what());
  }
}

TEST_F(HalPins, PinLinksToOneSignalOnly) {
  hal.link("fx.f-in", "a");
  hal.link("fx.f-in", "a");  // same signal again is fine
  EXPECT_THROW(hal.link("fx.f-in", "b"), HalError);
}

TEST_F(HalPins, SetpOnLinkedPinIsRefusedLikeLinuxCnc) {
  hal.link("fx.f-in", "sig");
  try {
    hal.set_pin_or_param("fx.f-in", "1");
    FAIL();
  } catch (const HalError& e) {
    EXPECT_NE(std::string(e.what()).find("is linked to signal 'sig'"), std::string::npos);
  }
}

TEST_F(HalPins, SetpOnOutputPinIsRefused) {
  EXPECT_THROW(hal.set_pin_or_param("fx.f-out", "1"), HalError);
}

TEST_F(HalPins, SetsOnSignalWithWriterIsRefusedWithoutWriterAccepted) {
  hal.link("fx.f-in", "in-only");
  hal.set_signal("in-only", "2.5");
  EXPECT_EQ(2.5, *fix.f_in);
  hal.link("fx.f-out", "driven");
  EXPECT_THROW(hal.set_signal("driven", "1"), HalError);
}

TEST_F(HalPins, ParametersReadWriteAndReadOnly) {
  EXPECT_EQ(2.0, hal.get_pin_or_param("fx.gain").f);
  hal.set_pin_or_param("fx.gain", "0.5");
  EXPECT_EQ(0.5, fix.gain_param);
  EXPECT_THROW(hal.set_pin_or_param("fx.ro", "1"), HalError);
  EXPECT_EQ(7, hal.get_pin_or_param("fx.ro").s);
  EXPECT_THROW(hal.link("fx.gain", "sig"), HalError) << "parameters cannot be linked";
}

TEST_F(HalPins, ValuesAreParsedPerType) {
  hal.set_pin_or_param("fx.b-in", "TRUE");
  EXPECT_TRUE(*fix.b_in);
  hal.set_pin_or_param("fx.b-in", "0");
  EXPECT_FALSE(*fix.b_in);
  hal.set_pin_or_param("fx.s-in", "-0x10");
  EXPECT_EQ(-16, *fix.s_in);
  EXPECT_THROW(hal.set_pin_or_param("fx.b-in", "2"), HalError);
  EXPECT_THROW(hal.set_pin_or_param("fx.s-in", "1.5"), HalError);
  EXPECT_THROW(hal.set_pin_or_param("fx.s-in", "3000000000"), HalError);
  EXPECT_THROW(hal.set_pin_or_param("fx.f-in", "1.0mm"), HalError);
  EXPECT_THROW(hal.set_pin_or_param("fx.f-in", "nan"), HalError);
}

TEST_F(HalPins, SignalNamesMustNotShadowPins) {
  EXPECT_THROW(hal.new_signal("fx.f-in", Type::kFloat), HalError);
  hal.new_signal("bits", Type::kBit);
  EXPECT_THROW(hal.new_signal("bits", Type::kBit), HalError);
  EXPECT_THROW(hal.link("fx.f-in", "bits"), HalError);
}

TEST_F(HalPins, IntrospectionListsPinsWithOwnerAndSignal) {
  hal.link("fx.f-out", "sig");
  bool seen = false;
  for (const auto& p : hal.pins()) {
    if (p.name != "fx.f-out") continue;
    seen = true;
    EXPECT_EQ("fx", p.owner);
    EXPECT_EQ("sig", p.signal);
    EXPECT_EQ(PinDir::kOut, p.dir);
  }
  EXPECT_TRUE(seen);
  auto sigs = hal.signals();
  ASSERT_EQ(1u, sigs.size());
  EXPECT_EQ(1, sigs[0].writers);
}
