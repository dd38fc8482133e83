//! The verifier: each rule rejects a project that breaks it, with its message; a project file's
//! problems are reported with their place; bad text never panics.

use asi_phy::SimDuration;
use safety::kl6904::connection::PartnerKind;
use safety::kl6904::project::{ConnectionOutputDesc, ModuleDesc, ModuleKind, Place, ProjectError};
use safety::kl6904::signal::{Contact, GroupOutput, SignalRef};
use safety::kl6904::verify::{Item, Rule, VerifyError};
use safety::kl6904::{Project, TwinSafeLogic};

fn ms(n: u64) -> SimDuration {
    SimDuration::from_millis(n)
}

fn std(name: &str) -> SignalRef {
    SignalRef::standard(name)
}

/// A small valid project: E-stop pair on a KL1904, K1 on local output 1.
fn base() -> Project {
    Project::new("test", 1)
        .group("g", std("ack"))
        .connection(
            "t",
            "g",
            PartnerKind::Kl1904,
            2,
            ms(100),
            &["a", "b", "aux"],
        )
        .module(
            ModuleDesc::new(ModuleKind::Estop, "estop", "g")
                .input("EStopIn1", SignalRef::twinsafe("t", "a"))
                .input("EStopIn2", SignalRef::twinsafe("t", "b"))
                .input("Restart", std("restart"))
                .input("EDM1", SignalRef::twinsafe("t", "aux"))
                .pair_discrepancy(&[ms(50)])
                .delay(ms(500)),
        )
        .local_output(1, "K1", "g", SignalRef::fb("estop", "EStopDelOut"))
        .standard_output("ok", SignalRef::fb("estop", "EStopOut"))
}

/// The one error `p` must produce, checked for its rule and a part of its message.
fn rejects(p: &Project, rule: Rule, message: &str) -> VerifyError {
    let errors = p.verify().expect_err("the project must be rejected");
    let hit = errors
        .iter()
        .find(|e| e.rule == rule && e.message.contains(message))
        .unwrap_or_else(|| panic!("no {rule:?} error containing {message:?} in {errors:#?}"));
    hit.clone()
}

#[test]
fn the_base_project_passes() {
    assert_eq!(base().verify(), Ok(()));
    assert!(TwinSafeLogic::new(&base()).is_ok());
}

#[test]
fn rule_unique_name() {
    let p = base().module(
        ModuleDesc::new(ModuleKind::And, "estop", "g")
            .input("AndIn1", SignalRef::twinsafe("t", 1))
            .input("AndIn2", SignalRef::twinsafe("t", 2)),
    );
    let e = rejects(
        &p,
        Rule::UniqueName,
        "the module name `estop` is used twice",
    );
    assert_eq!(
        e.item,
        Item::Module {
            index: 1,
            name: "estop".into()
        }
    );
    assert_eq!(
        e.to_string(),
        "module `estop`: the module name `estop` is used twice [rule: unique names]"
    );
    let mut p = base();
    p.connections[0].channels = vec!["a".into(), "a".into()];
    rejects(&p, Rule::UniqueName, "the channel name `a` is used twice");
}

#[test]
fn rule_one_group_connection_in_an_existing_group() {
    let mut p = base();
    p.connections[0].group = "nope".into();
    let e = rejects(
        &p,
        Rule::OneGroup,
        "belongs to group `nope`, which does not exist",
    );
    assert_eq!(
        e.item,
        Item::Connection {
            index: 0,
            name: "t".into()
        }
    );
}

#[test]
fn rule_one_group_connection_io_only_in_its_group() {
    let p = base().group("other", std("ack")).module(
        ModuleDesc::new(ModuleKind::Or, "or", "other")
            .input("OrIn1", SignalRef::twinsafe("t", "a")),
    );
    let e = rejects(
        &p,
        Rule::OneGroup,
        "`ts:t.a` belongs to group `g`; only modules of that group may use it",
    );
    assert_eq!(
        e.item,
        Item::ModuleInput {
            index: 1,
            name: "or".into(),
            input: "OrIn1".into()
        }
    );
}

#[test]
fn rule_one_group_local_output_driven_from_its_group() {
    let p = base().group("other", std("ack")).local_output(
        2,
        "K2",
        "other",
        SignalRef::fb("estop", "EStopOut"),
    );
    rejects(
        &p,
        Rule::OneGroup,
        "is in group `g`, but this output belongs to group `other`",
    );
}

#[test]
fn rule_driven_once() {
    let p = base().local_output(1, "K1b", "g", SignalRef::fb("estop", "EStopOut"));
    let e = rejects(
        &p,
        Rule::DrivenOnce,
        "local output 1 is already driven as `K1`",
    );
    assert_eq!(
        e.item,
        Item::LocalOutput {
            index: 1,
            name: "K1b".into()
        }
    );
    let p = base().standard_output("ok", SignalRef::fb("estop", "Error"));
    rejects(&p, Rule::DrivenOnce, "standard output `ok` is driven twice");
    let mut p = base().connection("out", "g", PartnerKind::Kl2904, 3, ms(100), &[]);
    let o = ConnectionOutputDesc {
        channel: 1,
        source: SignalRef::fb("estop", "EStopOut"),
    };
    p.connections[1].outputs = vec![o.clone(), o];
    rejects(
        &p,
        Rule::DrivenOnce,
        "TwinSAFE-Out channel 1 is driven twice",
    );
}

#[test]
fn rule_signal_kind_standard_signal_only_on_and_in1() {
    let ok = base().module(
        ModuleDesc::new(ModuleKind::And, "and", "g")
            .input_contact("AndIn1", std("overloaded"), Contact::Make)
            .input("AndIn2", SignalRef::fb("estop", "EStopOut")),
    );
    assert_eq!(
        ok.verify(),
        Ok(()),
        "a standard signal on AndIn1 is allowed"
    );
    let bad = base().module(
        ModuleDesc::new(ModuleKind::And, "and", "g")
            .input("AndIn1", SignalRef::fb("estop", "EStopOut"))
            .input("AndIn2", std("overloaded")),
    );
    let e = rejects(
        &bad,
        Rule::SignalKind,
        "AndIn2 of AND may be linked to TwinSAFE-In or FB-Out only, not to the Standard-In `std:overloaded`",
    );
    assert_eq!(
        e.item,
        Item::ModuleInput {
            index: 1,
            name: "and".into(),
            input: "AndIn2".into()
        }
    );
}

#[test]
fn rule_signal_kind_estop_inputs_and_group_inputs() {
    let mut p = base();
    p.modules[0]
        .inputs
        .insert("EStopIn3".into(), std("button").into());
    rejects(
        &p,
        Rule::SignalKind,
        "EStopIn3 of ESTOP may be linked to TwinSAFE-In or FB-Out only",
    );
    let mut p = base();
    p.groups[0].err_ack = Some(SignalRef::twinsafe("t", 1));
    rejects(
        &p,
        Rule::SignalKind,
        "ERR_ACK may be linked to FB-Out or Standard-In only",
    );
    let p = base().local_output(2, "x", "g", SignalRef::group("g", GroupOutput::ComErr));
    rejects(&p, Rule::SignalKind, "a Local-Out takes a module output");
}

#[test]
fn rule_unique_address() {
    let p = base().connection("t2", "g", PartnerKind::Kl1904, 2, ms(100), &[]);
    let e = rejects(
        &p,
        Rule::UniqueAddress,
        "partner address 2 is already used by connection `t`",
    );
    assert_eq!(
        e.item,
        Item::Connection {
            index: 1,
            name: "t2".into()
        }
    );
    let p = base().connection("t2", "g", PartnerKind::Kl1904, 1, ms(100), &[]);
    rejects(
        &p,
        Rule::UniqueAddress,
        "partner address 1 is already used by the logic `test`",
    );
    let mut p = base();
    p.logic.address = 0;
    rejects(&p, Rule::UniqueAddress, "TwinSAFE address 0 is not valid");
}

#[test]
fn rule_dangling_references() {
    let mut p = base();
    p.modules[0]
        .inputs
        .insert("EDM1".into(), SignalRef::twinsafe("t", "k2_aux").into());
    rejects(
        &p,
        Rule::Dangling,
        "connection `t` to a KL1904 has no input channel `k2_aux` (channels 1..4 or a, b, aux)",
    );
    let mut p = base();
    p.modules[0]
        .inputs
        .insert("EDM1".into(), SignalRef::twinsafe("t", 5).into());
    rejects(&p, Rule::Dangling, "has no input channel `5`");
    let p = base().standard_output("x", SignalRef::fb("estop", "EStopOutt"));
    rejects(
        &p,
        Rule::Dangling,
        "ESTOP module `estop` has no output `EStopOutt` (it has EStopOut, EStopDelOut, Error)",
    );
    let p = base().standard_output("x", SignalRef::fb("mon", "MonOut"));
    rejects(&p, Rule::Dangling, "there is no module `mon`");
    let p = base().standard_output("x", SignalRef::group("h", GroupOutput::FbErr));
    rejects(&p, Rule::Dangling, "there is no group `h`");
    let mut p = base();
    p.modules[0]
        .inputs
        .insert("EStopIn9".into(), std("x").into());
    let e = rejects(&p, Rule::Dangling, "ESTOP has no input `EStopIn9`");
    assert_eq!(
        e.item,
        Item::ModuleInput {
            index: 0,
            name: "estop".into(),
            input: "EStopIn9".into()
        }
    );
}

#[test]
fn rule_dangling_required_inputs() {
    let mut p = base();
    p.modules[0].inputs.remove("Restart");
    rejects(&p, Rule::Dangling, "Restart is not linked");
    let mut p = base();
    p.groups[0].err_ack = None;
    rejects(&p, Rule::Dangling, "ERR_ACK is not connected");
    let mut p = base();
    p.modules[0].inputs.remove("EStopIn2");
    rejects(
        &p,
        Rule::Dangling,
        "pair EStopIn1/EStopIn2 has a discrepancy time of 50 ms, so both inputs must be linked",
    );
    let p = base().module(ModuleDesc::new(ModuleKind::And, "and", "g").input("AndIn1", std("x")));
    rejects(&p, Rule::Dangling, "AND needs at least two inputs");
    let p = base().module(
        ModuleDesc::new(ModuleKind::OpMode, "mode", "g")
            .input("OpIn1", SignalRef::twinsafe("t", 1)),
    );
    rejects(&p, Rule::Dangling, "OPMODE needs at least two inputs");
    let p = base().module(
        ModuleDesc::new(ModuleKind::Mon, "mon", "g")
            .input("MonIn1", SignalRef::twinsafe("t", 1))
            .manual_restart(true),
    );
    rejects(
        &p,
        Rule::Dangling,
        "manual restart is on but Restart is not linked",
    );
}

#[test]
fn rule_dangling_decouple_inputs_and_outputs_come_in_pairs() {
    let p = base().module(
        ModuleDesc::new(ModuleKind::Decouple, "dec", "g")
            .input("DecIn1", SignalRef::twinsafe("t", 1)),
    );
    rejects(
        &p,
        Rule::Dangling,
        "DecIn1 is used but DecOut1 is not linked to anything",
    );
    let p = base()
        .module(ModuleDesc::new(ModuleKind::Decouple, "dec", "g"))
        .standard_output("x", SignalRef::fb("dec", "DecOut2"));
    rejects(
        &p,
        Rule::Dangling,
        "DecOut2 is linked but DecIn2 is not used",
    );
}

#[test]
fn rule_parameter() {
    let mut p = base();
    p.modules.push(
        ModuleDesc::new(ModuleKind::And, "and", "g")
            .input("AndIn1", SignalRef::twinsafe("t", 1))
            .input("AndIn2", SignalRef::twinsafe("t", 2))
            .delay(ms(10)),
    );
    let e = rejects(&p, Rule::Parameter, "AND has no parameter `delay`");
    assert_eq!(
        e.item,
        Item::ModuleParam {
            index: 1,
            name: "and".into(),
            param: "delay"
        }
    );
    let mut p = base();
    p.modules[0].pair_discrepancy = Some(vec![ms(1); 5]);
    rejects(
        &p,
        Rule::Parameter,
        "ESTOP has 4 input pairs, 5 discrepancy times given",
    );
    let mut p = base();
    p.modules[0]
        .inputs
        .get_mut("Restart")
        .expect("Restart")
        .contact = Some(Contact::Make);
    rejects(&p, Rule::Parameter, "Restart has no contact type");
    let mut p = base();
    p.connections[0].watchdog = SimDuration::ZERO;
    rejects(&p, Rule::Parameter, "the watchdog time must not be 0");
    let p = base().module(
        ModuleDesc::new(ModuleKind::Mon, "mon", "g")
            .input("MonIn1", SignalRef::twinsafe("t", 1))
            .input("Restart", std("reset")),
    );
    rejects(
        &p,
        Rule::Parameter,
        "Restart is linked but manual restart is off",
    );
}

#[test]
fn every_problem_is_reported_not_only_the_first() {
    let mut p = base();
    p.logic.address = 0;
    p.groups[0].err_ack = None;
    p.modules[0].inputs.remove("Restart");
    let errors = p.verify().expect_err("rejected");
    assert_eq!(errors.len(), 3, "{errors:#?}");
}

const FILE: &str = r#"[logic]
name = "f"
address = 1

[[group]]
name = "g"
err_ack = "std:ack"

[[module]]
kind = "ESTOP"
name = "estop"
group = "g"
inputs.EStopIn1 = "std:button"
inputs.Restart = "std:restart"
"#;

#[test]
fn a_file_problem_names_its_line_and_column() {
    let err = Project::from_toml("f.toml", FILE).expect_err("EStopIn1 must be safe");
    let ProjectError::Rejected { errors, .. } = &err else {
        panic!("expected a verifier error, got {err}");
    };
    assert_eq!(errors.len(), 1);
    assert_eq!(
        errors[0].0,
        Some(Place {
            line: 13,
            column: 19
        }),
        "the value of inputs.EStopIn1"
    );
    assert_eq!(
        err.to_string(),
        "f.toml: the verifier rejected the project (1 problem):\n  f.toml:13:19: module `estop`, input `EStopIn1`: \
         EStopIn1 of ESTOP may be linked to TwinSAFE-In or FB-Out only, not to the Standard-In `std:button` [rule: signal kinds]"
    );
}

#[test]
fn a_missing_input_points_at_its_module() {
    let text = FILE.replace("inputs.Restart = \"std:restart\"\n", "");
    let text = text.replace("\"std:button\"", "\"fb:estop.Error\"");
    let err = Project::from_toml("f.toml", &text).expect_err("Restart missing");
    let ProjectError::Rejected { errors, .. } = &err else {
        panic!("expected a verifier error, got {err}");
    };
    let place = errors[0].0.expect("placed");
    assert!(
        (9..=14).contains(&place.line),
        "inside the [[module]] table: {place}"
    );
}

#[test]
fn syntax_errors_name_the_place_and_cause() {
    for (text, line, needle) in [
        ("[logic]\nname = \"f\"\naddress = 1\n[[module]]\nkind = \"ESTOPP\"\n", 5, "ESTOPP"),
        ("[logic]\nname = \"f\"\naddress = 1\n[[group]]\nname = \"g\"\nerr_ack = \"ack\"\n", 6, "no `kind:` prefix"),
        ("[logic]\nname = \"f\"\naddress = 1\ncolour = \"red\"\n", 4, "colour"),
        ("[logic]\nname = \"f\"\naddress = 70000\n", 3, "70000"),
        ("[logic\n", 1, ""),
        (
            "[logic]\nname = \"f\"\naddress = 1\n[[connection]]\nname = \"c\"\ngroup = \"g\"\npartner = \"KL1904\"\npartner_address = 2\nwatchdog = \"100\"\n",
            9,
            "unknown unit",
        ),
    ] {
        let err = Project::from_toml("x.toml", text).expect_err(text);
        let ProjectError::Syntax { place, message, .. } = &err else {
            panic!("expected a syntax error for {text:?}, got {err}");
        };
        assert_eq!(place.map(|p| p.line), Some(line), "{text:?}: {err}");
        assert!(message.contains(needle), "{text:?}: {message}");
    }
}

#[test]
fn a_project_round_trips_through_toml() {
    let p = base().module(
        ModuleDesc::new(ModuleKind::And, "and", "g")
            .input_contact("AndIn1", std("overloaded"), Contact::Make)
            .input("AndIn2", SignalRef::fb("estop", "EStopDelOut")),
    );
    let text = p.to_toml().expect("serialisable");
    assert_eq!(Project::from_toml("p.toml", &text), Ok(p));
}
