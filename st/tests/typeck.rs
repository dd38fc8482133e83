//! Statements and expressions typed: a program that uses every construct is accepted, and a
//! corpus of wrong ones gets its messages (snapshots).

use st::check::check;
use st::parser::parse;
use st::source::Source;
use st::typeck::typecheck;

fn errors(text: &str) -> String {
    let src = Source::new("typed.st", text);
    let (unit, errors) = parse(&src);
    assert!(errors.is_empty(), "{}", src.render_all(&errors));
    let (c, errors) = check(&unit);
    assert!(errors.is_empty(), "{}", src.render_all(&errors));
    src.render_all(&typecheck(&c))
}

const GOOD: &str = r#"
TYPE
    Dir : (Stop, Up, Down);
    Station : STRUCT call : BOOL; shown : WORD; END_STRUCT;
END_TYPE
VAR_GLOBAL CONSTANT FLOORS : INT := 4; END_VAR

FUNCTION Clamp : INT
VAR_INPUT x, lo, hi : INT; END_VAR
    Clamp := LIMIT(lo, x, hi);
END_FUNCTION

FUNCTION_BLOCK Debounce
VAR_INPUT raw : BOOL; END_VAR
VAR_OUTPUT stable : BOOL; END_VAR
VAR t : TON; END_VAR
    t(IN := raw, PT := T#20ms, Q => stable);
END_FUNCTION_BLOCK

PROGRAM Lift
VAR
    d1 AT %IX2.3 : BOOL;
    run AT %QX7.0 : BOOL;
    setpoint AT %QW68 : WORD;
    here : INT (1..4) := 1;
    dir : Dir := Dir#Up;
    calls : ARRAY [1..4] OF BOOL;
    st : Station;
    deb : Debounce;
    edge : R_TRIG;
    count : CTU;
    i : INT;
    big : DINT;
    r : REAL;
    w : WORD;
    t : TIME;
END_VAR
    deb(raw := d1);
    edge(CLK := deb.stable);
    count(CU := edge.Q, R := FALSE, PV := 3);
    FOR i := 1 TO FLOORS BY 1 DO
        calls[i] := calls[i] OR st.call AND NOT deb.stable;
        IF i = here THEN EXIT; END_IF;
    END_FOR;
    CASE here OF
        1: dir := Dir#Up;
        2..3: dir := Down;
    ELSE
        dir := Stop;
    END_CASE;
    IF dir = Up AND count.Q THEN big := i + 100000; END_IF;
    WHILE i > 0 DO i := i - 1; END_WHILE;
    REPEAT i := i + 1; UNTIL i >= 10 END_REPEAT;
    w := SHL(w, 2) AND WORD#16#FF;
    w.3 := TRUE;
    r := INT_TO_REAL(i) * 2.5 + i;
    t := T#1s + T#500ms * 2;
    run := -2 ** 2 < r OR r / 2.0 >= 1.0 XOR w.%X4;
    setpoint := INT_TO_WORD(Clamp(x := 10000, lo := 4000, hi := 11000));
    big := MAX(big, i, 7);
END_PROGRAM
"#;

#[test]
fn a_program_with_every_construct_is_typed() {
    assert_eq!(errors(GOOD), "");
}

#[test]
fn wrong_statements_get_their_messages() {
    let corpus: &[(&str, &str)] = &[
        (
            "types",
            "PROGRAM P\nVAR i : INT; d : DINT; w : WORD; b : BOOL; r : REAL; u : UINT; END_VAR\n  i := d;\n  i := 40000;\n  w := i;\n  b := i;\n  r := d;\n  i := u + 1;\n  u := -u;\n  i := w + 1;\n  b := NOT 5;\nEND_PROGRAM\n",
        ),
        (
            "names_and_places",
            "VAR_GLOBAL CONSTANT K : INT := 1; END_VAR\nPROGRAM P\nVAR x AT %IX0.0 : BOOL; y : INT; END_VAR\n  x := TRUE;\n  K := 2;\n  %IW3 := 1;\n  nothing := 1;\n  y := unknown + 1;\n  P := 1;\nEND_PROGRAM\n",
        ),
        (
            "control",
            "TYPE Dir : (Up, Down); END_TYPE\nPROGRAM P\nVAR i : INT; r : REAL; d : Dir; END_VAR\n  IF i THEN i := 1; END_IF;\n  WHILE r DO EXIT; END_WHILE;\n  EXIT;\n  FOR r := 1 TO 3 DO END_FOR;\n  FOR i := 1 TO 3 DO i := i + 1; END_FOR;\n  CASE r OF 1: i := 2; END_CASE;\n  CASE d OF Up: i := 1; 3: i := 2; END_CASE;\nEND_PROGRAM\n",
        ),
        (
            "calls",
            "FUNCTION_BLOCK B VAR_INPUT a : BOOL; END_VAR VAR_OUTPUT q : BOOL; END_VAR VAR inner : INT; END_VAR END_FUNCTION_BLOCK\nPROGRAM P\nVAR b : B; t : TON; x : BOOL; i : INT; END_VAR\n  b(a := TRUE, q => x, z := 1);\n  b(TRUE);\n  i := b.inner;\n  x := t(IN := TRUE);\n  t(IN := 1, PT := 5, Q := x);\n  i := SHL(i, 1);\n  i := MIN(i, TRUE);\n  nothing(1);\nEND_PROGRAM\n",
        ),
        (
            "recursion_initial_values_labels",
            "TYPE S : STRUCT a : INT; END_STRUCT; Dir : (Up, Down); END_TYPE\nFUNCTION F : INT VAR_INPUT n : INT; END_VAR F := G(n); END_FUNCTION\nFUNCTION G : INT VAR_INPUT n : INT; END_VAR G := F(n); END_FUNCTION\nFUNCTION H : INT VAR_INPUT n : INT; END_VAR H := H(n - 1); END_FUNCTION\nPROGRAM P\nVAR\n  i : INT := 70000;\n  a : ARRAY [1..3] OF BOOL := [TRUE, 3(FALSE)];\n  s : S := (a := TRUE, b := 1);\n  d : Dir := Down;\n  x : INT := [1];\nEND_VAR\n  CASE i OF 1..5: ; 4: ; 6, 6: ; END_CASE;\n  CASE d OF Up: ; Dir#Up: ; END_CASE;\nEND_PROGRAM\n",
        ),
    ];
    for (name, text) in corpus {
        insta::assert_snapshot!(*name, errors(text));
    }
}
