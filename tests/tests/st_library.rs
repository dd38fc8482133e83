//! The lab's handshakes as Structured Text function blocks (`controllers/lab.st`), each
//! against the Rust slave on the whole rig: a program that uses them shows a display word on
//! the floor stations and the cabin display, reads the cabin panel's word, sees the hall
//! buttons pressed, and drives the current-loop output; the slaves show what it sent and the
//! program what they sent.

use asi_lift_tests::scenario;
use asi_phy::{SimDuration, SimTime};
use controller::structured::StProgram;
use lift_model::controls::Button;
use rig::scenario::{Action, Scenario};
use rig::Rig;
use st::run::Value;

const LAB: &str = include_str!("../../controllers/lab.st");

/// Floor 3, the up arrow, moving (tables 4.2/4.4).
fn word() -> u16 {
    lab::DisplayWord {
        floor: 3,
        up: true,
        moving: true,
        ..lab::DisplayWord::default()
    }
    .encode()
    .expect("a floor of the lab")
}

const PROGRAM: &str = "PROGRAM Probe
VAR
  Restart : BOOL;
  Overloaded : BOOL;
  t : TON;
  Floor1, Floor2, Floor3, Floor4 : FloorStation;
  Display : CabinDisplay;
  Panel : CabinPanel;
  Speed : CurrentOutput;
  Shown : WORD := 16#0000;
  UpPresses : ARRAY [1..4] OF INT;
  DownPresses : ARRAY [1..4] OF INT;
  PanelWords : DINT;
  VaneL, VaneR, Door : BOOL;
  SetPoint : UINT := 4000;
END_VAR
  t(IN := NOT t.Q, PT := T#500ms);
  Restart := t.Q;
  Overloaded := FALSE;
  Floor1(In := SlaveNibble(%IW0, 1), Display := Shown);
  Floor2(In := SlaveNibble(%IW0, 2), Display := Shown);
  Floor3(In := SlaveNibble(%IW0, 3), Display := Shown);
  Floor4(In := SlaveNibble(%IW1, 4), Display := Shown);
  %QW0 := WithNibble(WithNibble(WithNibble(%QW0, 1, Floor1.Out), 2, Floor2.Out), 3, Floor3.Out);
  %QW1 := WithNibble(%QW1, 4, Floor4.Out);
  IF Floor1.Up THEN UpPresses[1] := UpPresses[1] + 1; END_IF;
  IF Floor2.Up THEN UpPresses[2] := UpPresses[2] + 1; END_IF;
  IF Floor3.Up THEN UpPresses[3] := UpPresses[3] + 1; END_IF;
  IF Floor4.Up THEN UpPresses[4] := UpPresses[4] + 1; END_IF;
  IF Floor1.Down THEN DownPresses[1] := DownPresses[1] + 1; END_IF;
  IF Floor2.Down THEN DownPresses[2] := DownPresses[2] + 1; END_IF;
  IF Floor3.Down THEN DownPresses[3] := DownPresses[3] + 1; END_IF;
  IF Floor4.Down THEN DownPresses[4] := DownPresses[4] + 1; END_IF;
  Display(In := SlaveNibble(%IW1, 5), Display := Shown);
  %QW1 := WithNibble(%QW1, 5, Display.Out);
  Panel(In := SlaveNibble(%IW1, 6));
  %QW1 := WithNibble(%QW1, 6, Panel.Out);
  IF Panel.New THEN
    PanelWords := PanelWords + 1;
    VaneL := Panel.VaneLeft;
    VaneR := Panel.VaneRight;
    Door := Panel.DoorClosed;
  END_IF;
  Speed(MicroAmps := SetPoint);
  %QW68 := Speed.Word;
  (* The converter stays off: D0 = 0, D2 = 0 (1111 is no command). *)
  %QW1 := WithNibble(%QW1, 7, 0);
  Shown := WORD#@WORD@;

END_PROGRAM";

fn rig(sc: Scenario) -> Rig {
    let program = PROGRAM.replace("@WORD@", &word().to_string());
    let p = StProgram::compile_with(&[("lab.st", LAB)], "probe.st", &program)
        .unwrap_or_else(|e| panic!("{e}"));
    Rig::new(sc).expect("the rig").with_controller(p)
}

fn value(rig: &Rig, name: &str) -> Value {
    rig.controller::<StProgram>()
        .expect("the program")
        .value(name)
        .unwrap_or_else(|| panic!("{name}"))
}

/// The display word the program sends reaches every floor station and the cabin display
/// (tables 4.2–4.5), the current-loop output drives the set-point asked (table 2.2), and
/// the cabin panel's words (tables 4.6/4.7) come in whole and say what the panel holds.
#[test]
fn the_blocks_talk_to_the_lab_slaves() {
    let mut sc = scenario("demo");
    sc.duration = SimDuration::from_secs(10);
    let mut rig = rig(sc);
    run_to(&mut rig, 5_000);
    for f in 1..=4 {
        assert_eq!(
            rig.lab().floor(f).expect("station").display(),
            Some(word()),
            "floor {f}"
        );
    }
    let cabin = rig.lab().cabin_display().expect("cabin display").display();
    assert_eq!(cabin, Some(word()));
    let ua = rig.lab().analog_output().expect("the AC2618").current_ua(1);
    assert_eq!(ua, 4000);
    // The cabin stands between floors 2 and 3 (the demo's start): no vane, door closed.
    let s = *rig.lab().cabin_panel().expect("panel").signals();
    assert_eq!(value(&rig, "VaneL"), Value::Bool(s.vane_left));
    assert_eq!(value(&rig, "VaneR"), Value::Bool(s.vane_right));
    assert_eq!(value(&rig, "Door"), Value::Bool(true));
    let Value::Int(words) = value(&rig, "PanelWords") else {
        panic!("a DINT")
    };
    // A word is 14 steps of a scan or two each: some tens in 5 s.
    assert!(words >= 20, "{words} words");
    // The door opens: the next words say so.
    rig.schedule(SimTime::from_millis(5_000), Action::Door { closed: false });
    run_to(&mut rig, 6_000);
    assert_eq!(value(&rig, "Door"), Value::Bool(false));
}

/// A hall button held for a second is one press, at its floor and in its direction; a
/// second press after it was released is another (table 4.3).
#[test]
fn a_floor_station_reports_each_press_once() {
    let mut sc = scenario("demo");
    sc.duration = SimDuration::from_secs(30);
    sc.events.clear();
    let mut rig = rig(sc);
    let press = |button, at, hold| {
        (
            SimTime::from_millis(at),
            Action::Press {
                button,
                hold: SimDuration::from_millis(hold),
            },
        )
    };
    for (at, action) in [
        press(Button::HallUp(2), 2_000, 1_000),
        press(Button::HallDown(2), 4_000, 500),
    ] {
        rig.schedule(at, action);
    }
    run_to(&mut rig, 6_000);
    assert_eq!(element(&rig, "UpPresses", 2), 1);
    assert_eq!(element(&rig, "DownPresses", 2), 1);
    for f in [1, 3, 4] {
        assert_eq!(element(&rig, "UpPresses", f), 0);
        assert_eq!(element(&rig, "DownPresses", f), 0);
    }
}

fn element(rig: &Rig, array: &str, index: u32) -> i64 {
    let st = rig.controller::<StProgram>().expect("the program");
    match st.element(array, index - 1) {
        Some(Value::Int(n)) => n,
        v => panic!("{array}[{index}]: {v:?}"),
    }
}

/// Runs the rig's moments up to `ms`.
fn run_to(rig: &mut Rig, ms: u64) {
    while rig.step_until(SimTime::from_millis(ms)).is_some() {}
}
