//! The parser on whole programs: every construct of the language it reads, a corpus of wrong
//! programs with the messages a programmer gets (snapshots), and hostile sources.

use st::ast::*;
use st::parser::parse;
use st::source::Source;

fn parse_ok(text: &str) -> Unit {
    let src = Source::new("test.st", text);
    let (unit, errors) = parse(&src);
    assert!(errors.is_empty(), "{}", src.render_all(&errors));
    unit
}

fn messages(text: &str) -> String {
    let src = Source::new("wrong.st", text);
    let (_, errors) = parse(&src);
    src.render_all(&errors)
}

const EVERY_CONSTRUCT: &str = r#"
(* Types of every kind. *)
TYPE
    Dir : (Stop, Up, Down) := Stop;
    Level : (Low := 1, High := 4);
    Floor : INT (1..4);
    Calls : ARRAY [1..4] OF BOOL;
    Station : STRUCT
        call : BOOL;
        shown : WORD := 16#0F;
    END_STRUCT;
END_TYPE

VAR_GLOBAL CONSTANT
    FLOORS : INT := 4;
END_VAR

FUNCTION Clamp : INT
VAR_INPUT x, lo, hi : INT; END_VAR
    IF x < lo THEN Clamp := lo; ELSIF x > hi THEN Clamp := hi; ELSE Clamp := x; END_IF;
END_FUNCTION

FUNCTION_BLOCK Debounce
VAR_INPUT raw : BOOL; END_VAR
VAR_OUTPUT stable : BOOL; END_VAR
VAR t : TON; END_VAR
VAR_TEMP n : DINT; END_VAR
    t(IN := raw, PT := T#20ms, Q => stable);
END_FUNCTION_BLOCK

PROGRAM Lift
VAR
    d1 AT %IX2.3 : BOOL;
    run AT %QX7.0 : BOOL;
    setpoint AT %QW10 : WORD;
    here : Floor := 1;
    dir : Dir := Dir#Up;
    calls : Calls := [4(FALSE)];
    grid : ARRAY [1..2, 0..3] OF INT := [1, 2, 3, 4, 2(0), 7, 8];
    st : Station := (call := TRUE, shown := 2#0000_0101);
    deb : Debounce;
    i : INT;
    r : REAL := 1.5E2;
    w : WORD;
END_VAR
    deb(raw := d1);
    FOR i := 1 TO FLOORS BY 1 DO
        calls[i] := calls[i] OR st.call AND NOT deb.stable;
        IF i = here THEN EXIT; END_IF;
    END_FOR;
    CASE here OF
        1: dir := Dir#Up;
        2..3, 5: dir := Down;
            here := Clamp(here - 1, 1, 4);
        4: ;
    ELSE
        dir := Stop;
    END_CASE;
    WHILE i > 0 DO i := i - 1; END_WHILE;
    REPEAT i := i + 1; UNTIL i >= 10 END_REPEAT;
    w := SHL(w, 2) AND 16#FF;
    w.3 := TRUE;
    run := -2 ** 2 < INT#-3 OR r / 2.0 >= 1.0 XOR w.%X4;
    grid[1, 2] := 5 MOD 3;
    %QX7.1 := d1 & run;
    setpoint := INT_TO_WORD(Clamp(x := 10000, lo := 4000, hi := 11000));
    RETURN;
END_PROGRAM
"#;

#[test]
fn every_construct_parses() {
    let unit = parse_ok(EVERY_CONSTRUCT);
    assert_eq!(unit.items.len(), 5);
    let Item::Types(types) = &unit.items[0] else {
        panic!("TYPE first")
    };
    assert_eq!(types.len(), 5);
    assert!(matches!(&types[0].ty, TypeRef::Enum { values, .. } if values.len() == 3));
    assert!(matches!(&types[2].ty, TypeRef::Subrange { base, .. } if base.key() == "INT"));
    assert!(matches!(&types[4].ty, TypeRef::Struct { fields, .. } if fields.len() == 2));
    let Item::Pou(lift) = &unit.items[4] else {
        panic!("the program last")
    };
    assert_eq!(lift.kind, PouKind::Program);
    assert_eq!(lift.name.key(), "LIFT");
    let d1 = &lift.vars[0].decls[0];
    assert_eq!(
        d1.at.as_ref().map(|(d, _)| d.to_string()),
        Some("%IX2.3".into())
    );
    assert_eq!(lift.body.len(), 12);
    let Item::Pou(f) = &unit.items[2] else {
        panic!("the function")
    };
    assert!(matches!(&f.kind, PouKind::Function(TypeRef::Named(t)) if t.key() == "INT"));
}

/// `-2 ** 2 < INT#-3 OR …`: `**` before the sign, the comparison before OR, XOR before OR.
#[test]
fn operators_bind_as_the_standard_says() {
    let unit = parse_ok("PROGRAM P\n a := -2 ** 2 + 3 * 4 < 5 OR b AND c XOR d;\nEND_PROGRAM");
    let Item::Pou(p) = &unit.items[0] else {
        panic!("a program")
    };
    let StmtKind::Assign { value, .. } = &p.body[0].kind else {
        panic!("an assignment")
    };
    fn show(e: &Expr) -> String {
        match &e.kind {
            ExprKind::Lit(Lit::Int(n, _)) => n.to_string(),
            ExprKind::Name(i) => i.text.clone(),
            ExprKind::Unary(UnOp::Neg, x) => format!("(-{})", show(x)),
            ExprKind::Binary(op, a, b) => format!("({} {} {})", show(a), op.text(), show(b)),
            other => format!("{other:?}"),
        }
    }
    assert_eq!(
        show(value),
        "((((-(2 ** 2)) + (3 * 4)) < 5) OR ((b AND c) XOR d))"
    );
}

#[test]
fn wrong_programs_get_every_error_at_once() {
    let corpus: &[(&str, &str)] = &[
        (
            "missing_operand_and_semicolon",
            "PROGRAM P\nVAR x : INT; END_VAR\n  x := (3 + ;\n  x := 4\n  x := 5;\nEND_PROGRAM\n",
        ),
        (
            "equals_for_assignment",
            "PROGRAM P\n  x = 1;\n  IF x THEN y := 2; END_IF;\nEND_PROGRAM\n",
        ),
        (
            "unclosed_blocks",
            "PROGRAM P\n  IF a THEN\n    WHILE b DO\n      c := 1;\nEND_PROGRAM\n",
        ),
        (
            "bad_tokens",
            "PROGRAM P\n  x := 3#12 + T#5q;\n  y := 'open;\n  z := 1 ? 2;\nEND_PROGRAM\n",
        ),
        (
            "declarations",
            "PROGRAM P\nVAR\n  a : ;\n  b AT 5 : BOOL;\n  c : ARRAY [1..] OF INT;\n  d : INT := ;\nEND_VAR\nEND_PROGRAM\n",
        ),
        (
            "case_without_labels",
            "PROGRAM P\n  CASE x OF\n    := 3;\n    1: y := 1;\n  END_CASE;\nEND_PROGRAM\n",
        ),
        ("no_end", "PROGRAM P\n  x := 1;\n"),
        ("not_a_unit", "x := 1;\nPROGRAM P END_PROGRAM\n"),
    ];
    for (name, text) in corpus {
        insta::assert_snapshot!(*name, messages(text));
    }
}

/// Nesting beyond the bound is an error at its place, not a stack overflow; so is a long
/// source of anything.
#[test]
fn hostile_sources_are_refused_in_bounded_time() {
    let deep = format!(
        "PROGRAM P\n x := {}1{};\nEND_PROGRAM",
        "(".repeat(100_000),
        ")".repeat(100_000)
    );
    assert!(messages(&deep).contains("nested more than 64 deep"));
    let ifs = format!("PROGRAM P\n{}\nEND_PROGRAM", "IF a THEN ".repeat(10_000));
    assert!(messages(&ifs).contains("nested more than 64 deep"));
    let junk = "))]]:=;;END_IF ELSE %Q .. ** (*".repeat(20_000);
    let refused = messages(&junk);
    assert!(refused.contains("more errors after this one are not shown"));
    assert_eq!(refused.matches("junk.st:").count(), 0);
    assert_eq!(refused.matches("wrong.st:").count(), 101);
    let huge = "a".repeat(st::source::MAX_SOURCE_BYTES + 1);
    assert!(messages(&huge).contains("more than"));
}

mod random {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(256))]
        /// Any text: the parser ends, without a panic, and every error's place is within it.
        #[test]
        fn any_text_is_parsed_or_refused(text in "\\PC{0,400}") {
            let src = Source::new("any.st", text.clone());
            let (_, errors) = parse(&src);
            for e in &errors {
                prop_assert!(e.span.end as usize <= text.len());
                let _ = src.render(e);
            }
        }

        /// Pieces of Structured Text in any order: the same.
        #[test]
        fn any_token_soup_is_parsed_or_refused(
            pieces in proptest::collection::vec(prop::sample::select(vec![
                "PROGRAM", "P", "END_PROGRAM", "VAR", "END_VAR", "x", ":", "INT", ";", ":=",
                "1", "+", "(", ")", "IF", "THEN", "END_IF", "CASE", "OF", "..", ",", "[", "]",
                "ARRAY", "FOR", "TO", "DO", "END_FOR", "T#1s", "%IX0.1", "=>", ".", "#", "TYPE",
                "END_TYPE", "STRUCT", "END_STRUCT", "REPEAT", "UNTIL", "END_REPEAT", "NOT",
            ]), 0..200)
        ) {
            let text = pieces.join(" ");
            let src = Source::new("soup.st", text.clone());
            let (_, errors) = parse(&src);
            for e in &errors {
                prop_assert!(e.span.end as usize <= text.len());
            }
        }
    }
}
