// Executes one read block on the interpreter state in LinuxCNC's order of
// execution (comments, feed mode, F, S, T, M6, spindle, coolant, dwell,
// plane, units, compensation, tool length, coordinate system, path control,
// distance mode, G10/G28/G30/G92, motion, stop) and emits the canonical calls.
#pragma once

#include <optional>
#include <vector>

#include "arc_geometry.hpp"
#include "block.hpp"
#include "emitter.hpp"
#include "interp_state.hpp"
#include "modal_groups.hpp"
#include "parameters.hpp"
#include "truecut/interp/probe.hpp"
#include "truecut/interp/tool_table.hpp"

namespace truecut::interp {

// The largest whole-number word (T, H, D, M61 Q, arc P) a block may carry:
// int's range. No tool or turn count lies beyond it, and converting a
// larger value to int would be undefined.
inline constexpr double kLargestWholeWord = 2147483647.0;

class BlockExecutor {
 public:
  // Keeps its own copy of `tools`: G10 L1/L10/L11 edit it.
  BlockExecutor(InterpState& state, Parameters& params, const ToolTable& tools, Emitter& out)
      : s_(state), params_(params), tools_(tools), out_(out) {}

  // Answers the probing moves; null: standalone_probe.
  void set_probe(const ProbeFunction* probe) { probe_ = probe; }
  // Emits the calls LinuxCNC makes before the first block.
  // The coordinate system, its rotation and the G92 offsets the parameters
  // (a LinuxCNC parameter file) hold, as the controller starts.
  void restore_setup();
  void start_program();
  // Returns true when the block ends the program (M2, M30).
  bool execute(const Block& block, const LexedLine& line);
  // The program-end sequence (M2/M30).
  void end_program(bool pallet_shuttle);
  // A subroutine at call level `level` returns: its M73 state is restored
  // and its saved state forgotten (modal_state.cpp).
  void return_from_call(int level);

 private:
  [[noreturn]] void fail(int column, const std::string& message) const;
  int column_of(char letter) const;
  void comments();
  void feed_and_speed();
  void tool_select();
  void tool_change();
  // M62-M68, M19, M48-M53 (io_codes.cpp).
  void io_codes();
  void spindle_orient();
  void override_codes();
  // The block's `letter` as a whole number 0..largest, else a located error
  // naming `what`.
  int whole_word(char letter, double largest, const std::string& what) const;
  void spindle_and_coolant();
  void modal_state_codes();  // M70-M73 (modal_state.cpp)
  void modal_settings();
  void set_units(LengthUnits units);
  void select_coord_system(int index);
  void tool_length_offset();
  void dynamic_tool_length(int code);  // G43.1, G43.2
  void non_modal();
  void coord_system_data();
  void tool_table_edit(int l);    // G10 L1 L10 L11 (tool_table_edit.cpp)
  void loaded_tool_parameters();  // #5401..#5413 (tool_table_edit.cpp)
  void g92_offsets(int code);
  void set_origin_at_tool(int base);
  void go_home(int code);
  void motion();
  Axes6 target_position(bool machine_coords) const;
  void check_polar(Plane plane_before) const;
  // The XY end of the block's polar words (@ ^) from the program point
  // (x, y): G90 about the origin, G91 added to the point's own radius and
  // angle, as LinuxCNC does.
  void polar_point(double& x, double& y) const;
  void straight(bool rapid, const Axes6& target, int column);
  Axes6 move_base() const;  // where incremental and missing axis words count from
  void arc(bool clockwise, const Axes6& target);
  // G5 G5.1 G5.2 G5.3 (splines.cpp).
  void spline(int code, const Axes6& target, int column, bool axis_words);
  void cubic_or_quadratic(int code, const Axes6& target, int column, bool axis_words);
  void nurbs_point(const Axes6& target, int column, bool axis_words);
  void nurbs_end(int column, bool axis_words);
  // A G5.2 run left open when another motion code or the program end comes.
  void check_nurbs_closed(int column, const std::string& what) const;
  void canned_cycle(int code, int column);  // canned_cycles.cpp
  // G33 G33.1 (sync_motion.cpp) and G38.2-G38.5 (probing.cpp) to `target`.
  void sync_motion(int code, const Axes6& target, int column, bool axis_words);
  void probe(int code, const Axes6& target, int column, bool axis_words);
  // Cutter radius compensation (cutter_comp.cpp).
  void comp_on(int code);  // G41 G42 G41.1 G42.1
  void comp_off();         // G40
  void comp_flush();       // sends the held moves
  void check_comp_codes() const;
  void check_comp_plane_change(Plane next) const;
  // Moves the end of the held moves to (u, v) in the plane, with the gouge
  // checks (errors at `column`), and sends them.
  void move_held_end(double u, double v, int column);
  void comp_straight(bool rapid, const Axes6& target, int column);
  // `req` and `res`: the programmed arc from the programmed start.
  void comp_arc(const ArcRequest& req, const ArcResult& res, const Axes6& end, int column);
  void set_compensated_position(const Axes6& program_point);
  void check_feed(int column) const;
  void check_unused_words(int motion_code) const;
  void emit_offsets();
  std::string substitute_parameters(const std::string& text) const;

  // The modal state M70/M73 save (LinuxCNC 2.9's list) and M72 restores.
  struct ModalSnapshot {
    LengthUnits units;
    bool css;
    FeedMode feed_mode;
    double feed, speed;
    int spindle;
    bool mist, flood;
    Plane plane;
    int tool_length_code;
    int coord_index;
    PathMode path;
    double blend_tolerance, naive_tolerance;
    bool incremental, arc_absolute, retract_old_z;
  };
  struct SavedModal {
    std::optional<ModalSnapshot> state;
    bool autorestore = false;  // M73: restore when the subroutine returns
  };
  ModalSnapshot snapshot() const;
  void restore(const ModalSnapshot& saved);

  InterpState& s_;
  Parameters& params_;
  ToolTable tools_;
  Emitter& out_;
  const Block* b_ = nullptr;
  const LexedLine* line_ = nullptr;
  ModalCodes codes_;
  bool axes_used_ = false;               // axis words consumed by G10/G28/G30/G92
  Axes6 last_program_position_;          // end of the last move as emitted
  std::vector<SavedModal> saved_modal_;  // by call level
  const ProbeFunction* probe_ = nullptr;
};

}  // namespace truecut::interp
