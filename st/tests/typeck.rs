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

/// Hostile programs through the whole front end and the machine: the every-construct
/// program with its words deleted, doubled, swapped or replaced by other words of the
/// language. Each is refused with messages that name a place inside the source, or compiles
/// and runs 20 scans on a random image without a panic, each scan ending or faulting within
/// the watchdog's budget.
mod hostile {
    use super::GOOD;
    use proptest::prelude::*;
    use st::check::check;
    use st::parser::parse;
    use st::run::{Image, Plc};
    use st::source::Source;
    use st::typeck::typecheck;

    /// Words that reach the checker, the typer and the compiler in unusual places.
    const POOL: &[&str] = &[
        "INT",
        "DINT",
        "REAL",
        "BOOL",
        "WORD",
        "TIME",
        "Dir",
        "Station",
        "Debounce",
        "TON",
        "i",
        "r",
        "w",
        "t",
        "big",
        "here",
        "calls",
        "st",
        "deb",
        "FLOORS",
        "Clamp",
        "0",
        "1",
        "-1",
        "32767",
        "16#FFFF",
        "T#-5s",
        "1.0E38",
        "(",
        ")",
        "[",
        "]",
        ":=",
        "=>",
        ";",
        ",",
        ".",
        "..",
        "+",
        "-",
        "*",
        "/",
        "MOD",
        "**",
        "AND",
        "NOT",
        "IF",
        "THEN",
        "END_IF",
        "FOR",
        "TO",
        "BY",
        "DO",
        "END_FOR",
        "WHILE",
        "END_WHILE",
        "CASE",
        "OF",
        "END_CASE",
        "EXIT",
        "RETURN",
        "ARRAY",
        "[1..100000]",
        "VAR",
        "END_VAR",
        "AT",
        "%IW3",
        "%QX7.15",
        "%IW999",
        "Dir#Up",
        "RETURN;",
        "Lift",
        "FUNCTION",
        "PROGRAM",
    ];

    /// An edit of the program: lines (statements and declarations) deleted, doubled or
    /// swapped, or a name or literal replaced by another word (most such programs still
    /// parse, so the checker, the typer and the machine see them).
    #[derive(Clone, Debug)]
    enum Edit {
        Delete(usize),
        Double(usize),
        Swap(usize, usize),
        Replace(usize, usize),
    }

    fn edit() -> impl Strategy<Value = Edit> {
        prop_oneof![
            any::<usize>().prop_map(Edit::Delete),
            any::<usize>().prop_map(Edit::Double),
            (any::<usize>(), any::<usize>()).prop_map(|(a, b)| Edit::Swap(a, b)),
            (any::<usize>(), any::<usize>()).prop_map(|(a, b)| Edit::Replace(a, b)),
            (any::<usize>(), any::<usize>()).prop_map(|(a, b)| Edit::Replace(a, b)),
        ]
    }

    fn mutated(edits: &[Edit]) -> String {
        let mut lines: Vec<String> = GOOD.lines().map(str::to_owned).collect();
        for e in edits {
            let n = lines.len();
            if n == 0 {
                break;
            }
            match *e {
                Edit::Delete(i) => {
                    lines.remove(i % n);
                }
                Edit::Double(i) => lines.insert(i % n, lines[i % n].clone()),
                Edit::Swap(a, b) => lines.swap(a % n, b % n),
                Edit::Replace(at, w) => {
                    // The `at`-th name or number of the program, counted over all lines.
                    let words: Vec<(usize, usize, usize)> = lines
                        .iter()
                        .enumerate()
                        .flat_map(|(l, line)| {
                            let mut out = Vec::new();
                            let mut start = None;
                            for (k, ch) in line.char_indices().chain([(line.len(), ' ')]) {
                                let word = ch.is_ascii_alphanumeric() || ch == '_' || ch == '#';
                                match (start, word) {
                                    (None, true) => start = Some(k),
                                    (Some(s), false) => {
                                        out.push((l, s, k));
                                        start = None;
                                    }
                                    _ => {}
                                }
                            }
                            out
                        })
                        .collect();
                    if let Some(&(l, a, b)) = words.get(at % words.len().max(1)) {
                        lines[l].replace_range(a..b, POOL[w % POOL.len()]);
                    }
                }
            }
        }
        lines.join("\n")
    }

    struct Noise(Vec<u16>, Vec<u16>);

    impl Image for Noise {
        fn input(&self, w: u32) -> u16 {
            self.0[w as usize % self.0.len()]
        }
        fn output(&self, w: u32) -> u16 {
            self.1[w as usize % self.1.len()]
        }
        fn set_output(&mut self, w: u32, value: u16) {
            let n = self.1.len();
            self.1[w as usize % n] = value;
        }
    }

    proptest! {
        // 256 cases, or PROPTEST_CASES.
        #![proptest_config(ProptestConfig::default())]

        #[test]
        fn mutated_programs_are_refused_at_a_place_or_run_within_the_watchdog(
            edits in proptest::collection::vec(edit(), 1..6),
            image in proptest::collection::vec(any::<u16>(), 244),
        ) {
            let text = mutated(&edits);
            let src = Source::new("hostile.st", &text);
            let (unit, errors) = parse(&src);
            let errors = if errors.is_empty() {
                let (c, errors) = check(&unit);
                if errors.is_empty() {
                    let errors = typecheck(&c);
                    if errors.is_empty() {
                        let mut plc = Plc::new(&c);
                        let mut io = Noise(image, vec![0; 244]);
                        for k in 0..20i64 {
                            // A fault is an answer (the PLC goes to STOP); a panic or a hang is not.
                            if plc.scan(k * 10_000_000, &mut io).is_err() {
                                break;
                            }
                        }
                    }
                    errors
                } else {
                    errors
                }
            } else {
                errors
            };
            for e in &errors {
                prop_assert!(e.span.start as usize <= text.len() && e.span.end as usize <= text.len(), "{e:?} outside {} bytes", text.len());
            }
            let shown = src.render_all(&errors);
            prop_assert!(errors.is_empty() || shown.contains("hostile.st:"), "{shown}");
        }
    }
}
