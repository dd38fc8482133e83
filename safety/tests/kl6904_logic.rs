//! A KL6904 project running scan by scan: groups, ERR_ACK, connections over the black channel
//! (docs/safety-logic.md §9.2 "Group / connection"), DECOUPLE, OUT_ERR and the logic fault.

use asi_phy::{SimDuration, SimTime};
use safety::kl6904::connection::{ChannelFault, ConnDiag};
use safety::kl6904::group::GroupState;
use safety::kl6904::logic::{ConnectionId, LogicEventKind, StandardInput};
use safety::kl6904::modules::FbState;
use safety::kl6904::{Project, TwinSafeLogic};

/// §5.1 of the KL6904 manual (one E-stop, contactor K1 with EDM) with the E-stop on a KL1904 behind
/// a connection, plus a second group fed through DECOUPLE.
const MACHINE: &str = r#"
[logic]
name = "machine"
address = 1

[[group]]
name = "machine"
err_ack = "std:ack"

[[group]]
name = "beacon"
err_ack = "std:ack"

[[group]]
name = "bridge"
err_ack = "std:ack"

[[connection]]
name = "estop_terminal"
group = "bridge"
partner = "KL1904"
partner_address = 2
watchdog = "20ms"
channels = ["s1a", "s1b", "k1_aux"]

[[module]]
kind = "DECOUPLE"
name = "split"
group = "bridge"
inputs.DecIn1 = "ts:estop_terminal.s1a"
inputs.DecIn2 = "ts:estop_terminal.s1b"
inputs.DecIn3 = "ts:estop_terminal.k1_aux"

[[module]]
kind = "ESTOP"
name = "estop"
group = "machine"
delay = "100ms"
pair_discrepancy = ["10ms"]
inputs.EStopIn1 = "fb:split.DecOut1"
inputs.EStopIn2 = "fb:split.DecOut2"
inputs.Restart = "std:restart"
inputs.EDM1 = "fb:split.DecOut3"

[[module]]
kind = "AND"
name = "lamp"
group = "beacon"
inputs.AndIn1 = { signal = "std:lamp_off", contact = "make" }
inputs.AndIn2 = "fb:split.DecOut1"

[[local_output]]
index = 1
name = "K1"
group = "machine"
source = "fb:estop.EStopDelOut"

[[local_output]]
index = 2
name = "lamp"
group = "beacon"
source = "fb:lamp.AndOut"

[[standard_output]]
name = "estop_ok"
source = "fb:estop.EStopOut"

[[standard_output]]
name = "com_err"
source = "group:bridge.COM_ERR"
"#;

struct Rig {
    logic: TwinSafeLogic,
    terminal: ConnectionId,
    ack: StandardInput,
    restart: StandardInput,
    t: u64,
    log: Vec<String>,
}

impl Rig {
    fn new() -> Rig {
        let project = Project::from_toml("machine.toml", MACHINE).expect("valid project");
        let logic = TwinSafeLogic::new(&project).expect("verified");
        let terminal = logic.connection("estop_terminal").expect("connection");
        let ack = logic.standard_input("ack").expect("ack");
        let restart = logic.standard_input("restart").expect("restart");
        let mut rig = Rig {
            logic,
            terminal,
            ack,
            restart,
            t: 0,
            log: Vec::new(),
        };
        rig.contacts(true, true, true);
        rig
    }

    fn contacts(&mut self, s1a: bool, s1b: bool, k1_aux: bool) {
        let bits = u8::from(s1a) | u8::from(s1b) << 1 | u8::from(k1_aux) << 2;
        self.logic.set_partner_inputs(self.terminal, bits);
    }

    /// `n` scans of 1 ms.
    fn run(&mut self, n: u64) {
        for _ in 0..n {
            let events = self.logic.scan(SimTime::from_millis(self.t));
            self.log.extend(events.iter().map(|e| e.to_string()));
            self.t += 1;
        }
    }

    fn pulse(&mut self, input: StandardInput) {
        self.logic.set_standard_input(input, true);
        self.run(2);
        self.logic.set_standard_input(input, false);
        self.run(2);
    }

    fn k1(&self) -> bool {
        self.logic.local_output(1)
    }

    /// EStopOut as the PLC sees it.
    fn estop_ok(&self) -> bool {
        let o = self.logic.standard_output("estop_ok").expect("estop_ok");
        self.logic.standard_output_value(o)
    }

    /// Schedule `fault` on the terminal's channel at the next scan.
    fn inject_now(&mut self, fault: ChannelFault) {
        let at = SimTime::from_millis(self.t);
        self.logic.inject(self.terminal, at, fault);
    }

    fn logged(&self, needle: &str) -> bool {
        self.log.iter().any(|l| l.contains(needle))
    }

    fn diag(&self) -> ConnDiag {
        self.logic.connection_diag(self.terminal)
    }

    fn group(&self, name: &str) -> GroupState {
        let g = self.logic.group(name).expect("group");
        self.logic.group_status(g).state
    }

    fn started() -> Rig {
        let mut rig = Rig::new();
        rig.run(3);
        let restart = rig.restart;
        rig.pulse(restart);
        assert!(rig.k1(), "started: K1 on after the restart pulse");
        rig
    }
}

#[test]
fn the_project_starts_safe_and_runs_after_a_restart_pulse() {
    let mut rig = Rig::new();
    rig.run(5);
    assert!(!rig.k1(), "power-up: K1 off");
    assert_eq!(rig.group("machine"), GroupState::Run);
    assert_eq!(rig.diag(), ConnDiag(0), "connection running, no error");
    let restart = rig.restart;
    rig.pulse(restart);
    assert!(rig.k1());
    assert!(rig.logged("connection 1 `estop_terminal` running"));
    let signal = |text: &str| rig.logic.signal(&text.parse().expect(text));
    assert_eq!(signal("fb:estop.EStopOut"), Some(true));
    assert_eq!(signal("ts:estop_terminal.s1a"), Some(true));
    assert_eq!(signal("ts:estop_terminal.4"), Some(false), "unused channel");
    assert_eq!(signal("group:bridge.COM_ERR"), Some(false));
    assert_eq!(signal("std:restart"), Some(false));
    assert_eq!(signal("fb:nope.X"), None);
}

#[test]
fn a_connection_that_stops_sending_trips_com_err_until_acknowledged() {
    let mut rig = Rig::started();
    rig.inject_now(ChannelFault::Drop {
        duration: SimDuration::from_millis(50),
    });
    // the last valid telegram came 1 ms before the drop; 20 ms watchdog
    rig.run(20);
    assert_eq!(
        rig.diag(),
        ConnDiag(0),
        "within the watchdog time: no error"
    );
    assert!(rig.logic.local_output(2), "lamp still on");
    rig.run(1);
    assert!(
        rig.diag().contains(ConnDiag::WATCHDOG),
        "diag bit 2: {}",
        rig.diag()
    );
    assert!(rig.diag().contains(ConnDiag::FAIL_SAFE_VALUES));
    assert_eq!(rig.group("bridge"), GroupState::Error);
    let com_err = rig.logic.standard_output("com_err").expect("com_err");
    assert!(rig.logic.standard_output_value(com_err), "COM_ERR output");
    assert!(
        !rig.estop_ok(),
        "fail-safe values: the E-stop inputs read 0, EStopOut off"
    );
    assert!(
        rig.k1(),
        "K1 follows EStopDelOut: off only after the 100 ms delay"
    );
    assert!(
        !rig.logic.local_output(2),
        "DecOut forced 0: the lamp is off too"
    );
    assert_eq!(
        rig.group("machine"),
        GroupState::Run,
        "DECOUPLE keeps the other groups running"
    );
    assert!(rig.logged("COM_ERR: watchdog expired on connection 1 `estop_terminal`: no valid telegram for 21 ms (watchdog 20 ms)"));

    // acknowledgement while the link is still down is refused
    let ack = rig.ack;
    rig.pulse(ack);
    assert_eq!(rig.group("bridge"), GroupState::Error);
    // telegrams flow again, but that alone does not clear the error
    rig.run(40);
    assert!(rig.diag().contains(ConnDiag::WATCHDOG));
    assert!(
        rig.diag().contains(ConnDiag::SLAVE_ERROR),
        "the terminal's own watchdog expired too: {}",
        rig.diag()
    );
    assert!(!rig.logic.local_output(2));
    rig.pulse(ack);
    assert_eq!(rig.group("bridge"), GroupState::Run);
    assert_eq!(rig.diag(), ConnDiag(0));
    assert!(
        rig.logic.local_output(2),
        "the lamp (AND, no restart) follows at once"
    );
    assert!(
        rig.k1(),
        "the E-stop delay (100 ms from the trip at 27 ms) is still running"
    );
    rig.run(60);
    assert!(
        !rig.k1(),
        "ESTOP saw its inputs drop: after the delay it needs a restart"
    );
    let restart = rig.restart;
    rig.pulse(restart);
    assert!(rig.k1());
}

#[test]
fn a_drop_shorter_than_the_watchdog_is_tolerated() {
    let mut rig = Rig::started();
    rig.inject_now(ChannelFault::Drop {
        duration: SimDuration::from_millis(15),
    });
    rig.run(100);
    assert_eq!(rig.diag(), ConnDiag(0));
    assert!(rig.k1());
}

#[test]
fn one_corrupted_crc_is_a_crc_error() {
    let mut rig = Rig::started();
    let at = SimTime::from_millis(rig.t + 3);
    rig.logic.inject(rig.terminal, at, ChannelFault::CorruptCrc);
    rig.run(3);
    assert_eq!(rig.diag(), ConnDiag(0));
    rig.run(1);
    assert_eq!(
        rig.diag(),
        ConnDiag::CRC | ConnDiag::FAIL_SAFE_VALUES,
        "diag bit 3"
    );
    assert!(!rig.estop_ok());
    assert!(rig.logged("COM_ERR: CRC error on connection 1"));
    rig.run(5);
    let ack = rig.ack;
    rig.pulse(ack);
    assert_eq!(
        rig.diag(),
        ConnDiag(0),
        "next telegrams valid: the ack is accepted"
    );
}

#[test]
fn one_replayed_telegram_is_a_sequence_error() {
    let mut rig = Rig::started();
    rig.inject_now(ChannelFault::Replay { age: 1 });
    rig.run(1);
    assert_eq!(
        rig.diag(),
        ConnDiag::SEQUENCE | ConnDiag::FAIL_SAFE_VALUES,
        "diag bit 4"
    );
    assert!(rig.logged("sequence error"), "{:?}", rig.log);
    rig.run(3);
    let ack = rig.ack;
    rig.pulse(ack);
    assert_eq!(rig.diag(), ConnDiag(0));
}

#[test]
fn a_telegram_from_the_wrong_address_is_rejected() {
    let mut rig = Rig::started();
    rig.inject_now(ChannelFault::WrongAddress { sender: 7 });
    rig.run(1);
    assert!(rig.diag().contains(ConnDiag::CRC));
    assert!(rig.logged("telegram from TwinSAFE address 7, expected 2"));
}

#[test]
fn a_null_telegram_sets_bit_0() {
    let mut rig = Rig::started();
    rig.inject_now(ChannelFault::NullTelegram);
    rig.run(1);
    assert!(rig.diag().contains(ConnDiag::NULL_TELEGRAM));
    assert!(!rig.estop_ok());
    assert!(rig.k1(), "delayed output still on");
    rig.run(100);
    assert!(!rig.k1(), "off after the delay");
}

#[test]
fn an_estop_discrepancy_trips_fb_err_and_err_ack_plus_restart_recovers() {
    let mut rig = Rig::started();
    rig.contacts(false, true, true);
    rig.run(11);
    assert_eq!(
        rig.group("machine"),
        GroupState::Run,
        "10 ms: within the discrepancy time"
    );
    assert!(
        !rig.estop_ok() && rig.k1(),
        "a demand: EStopOut off, the delay runs"
    );
    rig.run(1);
    assert_eq!(rig.group("machine"), GroupState::Error);
    let m = rig.logic.module("estop").expect("estop");
    assert_eq!(rig.logic.module_status(m).diag, 0b1);
    assert_eq!(rig.logic.module_status(m).state, FbState::Error);
    assert!(!rig.k1());
    let ack = rig.ack;
    rig.pulse(ack);
    assert_eq!(
        rig.group("machine"),
        GroupState::Error,
        "pair still disagrees: ack refused"
    );
    rig.contacts(true, true, true);
    rig.run(1);
    rig.pulse(ack);
    assert_eq!(rig.group("machine"), GroupState::Run);
    assert!(!rig.k1(), "after ERR_ACK the module waits for its restart");
    let restart = rig.restart;
    rig.pulse(restart);
    assert!(rig.k1());
}

#[test]
fn a_welded_contactor_refuses_the_restart_with_an_edm_error() {
    let mut rig = Rig::new();
    rig.contacts(true, true, false);
    rig.run(3);
    let restart = rig.restart;
    rig.pulse(restart);
    assert!(!rig.k1());
    let m = rig.logic.module("estop").expect("estop");
    assert_eq!(rig.logic.module_status(m).diag, 1 << 4, "diag bit 4: EDM1");
    assert!(rig.logged("FB_ERR: ESTOP `estop`: EDM1 not 1 at restart"));
}

#[test]
fn a_local_output_error_trips_out_err() {
    let mut rig = Rig::started();
    rig.logic.set_local_output_fault(1, true);
    rig.run(1);
    assert!(!rig.k1());
    let g = rig.logic.group("machine").expect("group");
    assert!(rig.logic.group_status(g).errors.out_err);
    rig.logic.set_local_output_fault(1, false);
    let ack = rig.ack;
    rig.pulse(ack);
    assert!(!rig.logic.group_status(g).errors.out_err);
}

#[test]
fn a_logic_fault_stops_everything_for_good() {
    let mut rig = Rig::started();
    rig.logic.inject_logic_fault("RAM test failed");
    rig.run(1);
    assert!(!rig.k1() && !rig.logic.local_output(2));
    assert_eq!(rig.logic.logic_fault(), Some("RAM test failed"));
    let ack = rig.ack;
    rig.pulse(ack);
    let restart = rig.restart;
    rig.pulse(restart);
    assert!(!rig.k1(), "no acknowledgement leaves a logic fault");
}

#[test]
fn time_running_backwards_is_a_logic_fault() {
    let mut rig = Rig::started();
    let events = rig.logic.scan(SimTime::from_millis(1));
    assert!(events
        .iter()
        .any(|e| matches!(e.kind, LogicEventKind::LogicFault { .. })));
    assert!(!rig.k1());
}

#[test]
fn run_false_stops_the_group_and_a_restart_is_needed_after_it_returns() {
    use safety::kl6904::project::{ModuleDesc, ModuleKind};
    use safety::kl6904::signal::SignalRef;
    let mut project = Project::new("run", 1).group("g", SignalRef::standard("ack"));
    project.groups[0].run = Some(SignalRef::standard("run"));
    let project = project
        .module(
            ModuleDesc::new(ModuleKind::Estop, "estop", "g")
                // its own Error output as a make contact: a safe input that never demands
                .input_contact(
                    "EStopIn1",
                    SignalRef::fb("estop", "Error"),
                    safety::kl6904::signal::Contact::Make,
                )
                .input("Restart", SignalRef::standard("restart")),
        )
        .local_output(1, "K", "g", SignalRef::fb("estop", "EStopOut"));
    let mut logic = TwinSafeLogic::new(&project).expect("valid");
    let run = logic.standard_input("run").expect("run");
    let restart = logic.standard_input("restart").expect("restart");
    let g = logic.group("g").expect("g");
    let mut t = 0;
    let mut scan = |logic: &mut TwinSafeLogic, run_v: bool, restart_v: bool| {
        logic.set_standard_input(run, run_v);
        logic.set_standard_input(restart, restart_v);
        logic.scan(SimTime::from_millis(t));
        t += 1;
    };
    scan(&mut logic, false, false);
    assert_eq!(logic.group_status(g).state, GroupState::Stop, "RUN = FALSE");
    for r in [false, true, false] {
        scan(&mut logic, false, r);
    }
    assert!(!logic.local_output(1), "stopped: no restart possible");
    for r in [false, true, false] {
        scan(&mut logic, true, r);
    }
    assert!(logic.local_output(1));
    scan(&mut logic, false, false);
    assert!(!logic.local_output(1), "RUN = FALSE: outputs safe at once");
    scan(&mut logic, true, false);
    assert!(
        !logic.local_output(1),
        "back in RUN: the module starts in its safe state"
    );
}

/// Two groups on two terminals: `a` (RUN from a standard input) holds AND `a0`, then an
/// OPMODE `m` that errors when no mode is selected for 5 ms; `b` holds AND `b1`, which reads
/// `a0` across the group boundary.
fn two_groups() -> TwinSafeLogic {
    use safety::kl6904::connection::PartnerKind;
    use safety::kl6904::project::{ModuleDesc, ModuleKind};
    use safety::kl6904::signal::SignalRef;
    let (ts, std) = (SignalRef::twinsafe, SignalRef::standard);
    let ms = SimDuration::from_millis;
    let mut p = Project::new("two", 1)
        .group("a", std("ack"))
        .group("b", std("ack"))
        .connection("ta", "a", PartnerKind::Kl1904, 2, ms(100), &[])
        .connection("tb", "b", PartnerKind::Kl1904, 3, ms(100), &[])
        .module(
            ModuleDesc::new(ModuleKind::And, "a0", "a")
                .input("AndIn1", std("x"))
                .input("AndIn2", ts("ta", 1)),
        )
        .module(
            ModuleDesc::new(ModuleKind::OpMode, "m", "a")
                .input("OpIn1", ts("ta", 2))
                .input("OpIn2", ts("ta", 3))
                .discrepancy(ms(5)),
        )
        .module(
            ModuleDesc::new(ModuleKind::And, "b1", "b")
                .input("AndIn1", ts("tb", 1))
                .input("AndIn2", SignalRef::fb("a0", "AndOut")),
        )
        .standard_output("a_out", SignalRef::fb("a0", "AndOut"))
        .standard_output("b_out", SignalRef::fb("b1", "AndOut"));
    p.groups[0].run = Some(std("run_a"));
    let mut logic = TwinSafeLogic::new(&p).expect("valid");
    for (name, v) in [("x", true), ("run_a", true)] {
        let h = logic.standard_input(name).expect(name);
        logic.set_standard_input(h, v);
    }
    let ta = logic.connection("ta").expect("ta");
    let tb = logic.connection("tb").expect("tb");
    logic.set_partner_inputs(ta, 0b011); // mode 1 selected
    logic.set_partner_inputs(tb, 0b001);
    logic
}

fn std_out(logic: &TwinSafeLogic, name: &str) -> bool {
    logic.standard_output_value(logic.standard_output(name).expect(name))
}

#[test]
fn a_stopped_group_outputs_zero_to_readers_in_other_groups_in_the_same_scan() {
    let mut logic = two_groups();
    logic.scan(SimTime::from_millis(0));
    assert!(std_out(&logic, "b_out"), "both groups run: b1 = a0 = 1");
    let run_a = logic.standard_input("run_a").expect("run_a");
    logic.set_standard_input(run_a, false);
    logic.scan(SimTime::from_millis(1));
    assert!(!std_out(&logic, "a_out"));
    assert!(
        !std_out(&logic, "b_out"),
        "b1 read a0 as 0 in the scan group a stopped"
    );
}

#[test]
fn a_module_error_zeroes_its_group_in_the_scan_it_is_found() {
    let mut logic = two_groups();
    logic.scan(SimTime::from_millis(0));
    assert!(std_out(&logic, "a_out"));
    let ta = logic.connection("ta").expect("ta");
    logic.set_partner_inputs(ta, 0b001); // no mode selected
    let a = logic.group("a").expect("a");
    for t in 1..20 {
        logic.scan(SimTime::from_millis(t));
        if logic.group_status(a).state == GroupState::Error {
            assert_eq!(t, 7, "invalid from 1 ms, longer than 5 ms at 7 ms");
            assert!(
                !std_out(&logic, "a_out"),
                "a0 ran before m, yet its output is 0 now"
            );
            assert!(
                std_out(&logic, "b_out"),
                "b1 (another group) read a0 before the trip: it sees 0 one scan later"
            );
            logic.scan(SimTime::from_millis(t + 1));
            assert!(!std_out(&logic, "b_out"));
            return;
        }
        assert!(std_out(&logic, "a_out"), "t = {t}");
    }
    panic!("OPMODE never reported its discrepancy error");
}

#[test]
fn twinsafe_out_reaches_a_kl2904_and_fails_safe_on_a_lost_link() {
    use safety::kl6904::connection::PartnerKind;
    use safety::kl6904::project::{ConnectionOutputDesc, ModuleDesc, ModuleKind};
    use safety::kl6904::signal::SignalRef;
    let ms = SimDuration::from_millis;
    let mut p = Project::new("out", 1)
        .group("g", SignalRef::standard("ack"))
        .connection("in", "g", PartnerKind::Kl1904, 2, ms(20), &[])
        .connection("out", "g", PartnerKind::Kl2904, 3, ms(20), &[])
        .module(
            ModuleDesc::new(ModuleKind::And, "and", "g")
                .input("AndIn1", SignalRef::twinsafe("in", 1))
                .input("AndIn2", SignalRef::twinsafe("in", 2)),
        );
    p.connections[1].outputs = vec![ConnectionOutputDesc {
        channel: 3,
        source: SignalRef::fb("and", "AndOut"),
    }];
    let mut logic = TwinSafeLogic::new(&p).expect("valid");
    let (cin, cout) = (
        logic.connection("in").expect("in"),
        logic.connection("out").expect("out"),
    );
    logic.set_partner_inputs(cin, 0b11);
    for t in 0..3 {
        logic.scan(SimTime::from_millis(t));
    }
    assert_eq!(
        logic.partner_outputs(cout),
        0b100,
        "channel 3 on at the KL2904"
    );
    logic.set_partner_inputs(cin, 0b01);
    logic.scan(SimTime::from_millis(3));
    logic.scan(SimTime::from_millis(4));
    assert_eq!(
        logic.partner_outputs(cout),
        0,
        "follows the AND one exchange later"
    );
    logic.set_partner_inputs(cin, 0b11);
    logic.scan(SimTime::from_millis(5));
    logic.scan(SimTime::from_millis(6));
    assert_eq!(logic.partner_outputs(cout), 0b100);
    logic.inject(
        cout,
        SimTime::from_millis(7),
        ChannelFault::Drop { duration: ms(100) },
    );
    // the last valid exchange was at 6 ms; both watchdogs (20 ms) expire after 26 ms
    for t in 7..=26 {
        logic.scan(SimTime::from_millis(t));
    }
    assert_eq!(
        logic.partner_outputs(cout),
        0b100,
        "20 ms: the terminal's watchdog holds"
    );
    assert_eq!(logic.connection_diag(cout), ConnDiag(0));
    logic.scan(SimTime::from_millis(27));
    assert_eq!(
        logic.partner_outputs(cout),
        0,
        "the KL2904's own watchdog: outputs safe"
    );
    assert!(logic.connection_diag(cout).contains(ConnDiag::WATCHDOG));
}
