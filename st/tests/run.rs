//! Programs run scan by scan against an image: arithmetic in each type's width, control flow,
//! function blocks (the standard's and the program's own) keeping their state between scans,
//! functions, located variables on the image, and the faults that stop the PLC.

use st::check::check;
use st::parser::parse;
use st::run::{Budget, FaultCause, Image, Plc, Value};
use st::source::Source;
use st::typeck::typecheck;

#[derive(Default)]
struct Words {
    input: Vec<u16>,
    output: Vec<u16>,
}

impl Image for Words {
    fn input(&self, w: u32) -> u16 {
        self.input.get(w as usize).copied().unwrap_or(0)
    }
    fn output(&self, w: u32) -> u16 {
        self.output.get(w as usize).copied().unwrap_or(0)
    }
    fn set_output(&mut self, w: u32, value: u16) {
        if let Some(o) = self.output.get_mut(w as usize) {
            *o = value;
        }
    }
}

fn words() -> Words {
    Words {
        input: vec![0; 16],
        output: vec![0; 16],
    }
}

fn plc(text: &str) -> (Plc, Source) {
    let src = Source::new("run.st", text);
    let (unit, errors) = parse(&src);
    assert!(errors.is_empty(), "{}", src.render_all(&errors));
    let (c, errors) = check(&unit);
    assert!(errors.is_empty(), "{}", src.render_all(&errors));
    let errors = typecheck(&c);
    assert!(errors.is_empty(), "{}", src.render_all(&errors));
    (Plc::new(&c), src)
}

fn int(p: &Plc, name: &str) -> i64 {
    match p.get(name) {
        Some(Value::Int(i)) => i,
        Some(Value::Uint(u)) => u as i64,
        Some(Value::Bool(b)) => i64::from(b),
        other => panic!("{name}: {other:?}"),
    }
}

fn real(p: &Plc, name: &str) -> f64 {
    match p.get(name) {
        Some(Value::Real(r)) => r,
        other => panic!("{name}: {other:?}"),
    }
}

const MS: i64 = 1_000_000;

#[test]
fn arithmetic_in_each_types_width() {
    let (mut p, _) = plc(
        "PROGRAM P
VAR i : INT := 32767; u : UINT; s : SINT := -128; d : DINT; r : REAL; q : INT; w : WORD := 16#F0F0; b : BYTE; m : INT; x : LREAL; END_VAR
  i := i + 1;
  u := u - 1;
  s := s - 1;
  d := 7 / 2 * 2 + 7 MOD 3;
  r := 1.0 / 3.0;
  x := 1.0 / 3.0;
  q := REAL_TO_INT(2.5) + REAL_TO_INT(-2.6);
  w := NOT w AND 16#FF00 OR SHL(WORD#1, 3);
  b := ROL(BYTE#16#81, 1);
  m := -7 MOD 3;
END_PROGRAM",
    );
    p.scan(0, &mut words()).expect("a scan");
    assert_eq!(int(&p, "i"), -32768, "INT wraps");
    assert_eq!(int(&p, "u"), 65535, "UINT wraps");
    assert_eq!(int(&p, "s"), 127, "SINT wraps");
    assert_eq!(int(&p, "d"), 7);
    assert_eq!(
        real(&p, "r"),
        f64::from(1.0f32 / 3.0),
        "REAL is single precision"
    );
    assert_eq!(real(&p, "x"), 1.0 / 3.0);
    assert_eq!(int(&p, "q"), 0, "REAL_TO_INT rounds: 3 and -3");
    assert_eq!(int(&p, "w"), 0x0F08);
    assert_eq!(int(&p, "b"), 0x03);
    assert_eq!(int(&p, "m"), -1, "MOD keeps the dividend's sign");
}

#[test]
fn control_flow() {
    let (mut p, _) = plc("TYPE Dir : (Stop, Up := 5, Down); END_TYPE
PROGRAM P
VAR sum, n, k, c : INT; d : Dir := Down; a : ARRAY [1..5] OF INT; found : INT; END_VAR
  sum := 0;
  FOR n := 1 TO 10 DO
    IF n = 8 THEN EXIT; END_IF;
    IF n MOD 2 = 0 THEN CONTINUE; END_IF;
    sum := sum + n;
  END_FOR;
  k := 0;
  WHILE k < 100 DO k := k + 7; END_WHILE;
  REPEAT c := c + 1; UNTIL c >= 3 END_REPEAT;
  CASE d OF Stop: found := 1; Up: found := 2; Down: found := 3; END_CASE;
  FOR n := 5 TO 1 BY -1 DO a[n] := n * n; END_FOR;
  CASE a[3] OF 1..8: found := found * 10; 9, 10: found := found * 100; ELSE found := -1; END_CASE;
END_PROGRAM");
    p.scan(0, &mut words()).expect("a scan");
    assert_eq!(int(&p, "sum"), 1 + 3 + 5 + 7);
    assert_eq!(int(&p, "k"), 105);
    assert_eq!(int(&p, "c"), 3);
    assert_eq!(int(&p, "found"), 300);
}

/// A TON on the image: the output bit follows the input bit 200 ms late, scan by scan; a
/// block of the program counts the input's rising edges in an array of instances.
#[test]
fn blocks_keep_their_state_between_scans() {
    let (mut p, _) = plc("FUNCTION_BLOCK Counter
VAR_INPUT pulse : BOOL; END_VAR
VAR_OUTPUT count : INT; END_VAR
VAR edge : R_TRIG; END_VAR
  edge(CLK := pulse);
  IF edge.Q THEN count := count + 1; END_IF;
END_FUNCTION_BLOCK
PROGRAM P
VAR
  button AT %IX2.3 : BOOL;
  lamp AT %QX5.0 : BOOL;
  t : TON;
  counters : ARRAY [0..1] OF Counter;
  n0, n1 : INT;
END_VAR
  t(IN := button, PT := T#200ms, Q => lamp);
  counters[1](pulse := button);
  n1 := counters[1].count;
  n0 := counters[0].count;
END_PROGRAM");
    let mut img = words();
    let mut lamp_at = None;
    for k in 0..60 {
        let now = k * 10 * MS;
        // The button is pressed 100–450 ms and 500–510 ms.
        let pressed = (100..450).contains(&(k * 10)) || (500..510).contains(&(k * 10));
        img.input[2] = if pressed { 1 << 3 } else { 0 };
        p.scan(now, &mut img).expect("a scan");
        let lamp = img.output[5] & 1 == 1;
        if lamp && lamp_at.is_none() {
            lamp_at = Some(k * 10);
        }
        if k * 10 == 450 {
            assert!(!lamp, "the lamp goes out with the button");
        }
    }
    assert_eq!(lamp_at, Some(300), "TON: 200 ms after the press at 100 ms");
    assert_eq!(int(&p, "n1"), 2, "two presses");
    assert_eq!(int(&p, "n0"), 0, "the other instance saw nothing");
}

#[test]
fn functions_start_from_their_initial_values_at_each_call() {
    let (mut p, _) = plc("FUNCTION Acc : INT
VAR_INPUT x : INT; END_VAR
VAR total : INT := 100; END_VAR
  total := total + x;
  Acc := total;
END_FUNCTION
PROGRAM P
VAR a, b : INT; END_VAR
  a := Acc(1);
  b := Acc(x := 2);
END_PROGRAM");
    p.scan(0, &mut words()).expect("a scan");
    assert_eq!((int(&p, "a"), int(&p, "b")), (101, 102));
}

#[test]
fn faults_stop_the_plc_at_their_place() {
    let (mut p, src) = plc("PROGRAM P
VAR i, z : INT; a : ARRAY [1..3] OF INT; END_VAR
  i := 10 / z;
END_PROGRAM");
    let f = p.scan(0, &mut words()).expect_err("a division by zero");
    assert_eq!(f.cause, FaultCause::DivisionByZero);
    assert_eq!(src.locate(f.span.start).0, 3);

    let (mut p, src) = plc("PROGRAM P
VAR i : INT := 4; a : ARRAY [1..3] OF INT; END_VAR
  a[i] := 1;
END_PROGRAM");
    let f = p.scan(0, &mut words()).expect_err("an index out of range");
    assert_eq!(
        f.cause,
        FaultCause::IndexOutOfRange {
            index: 4,
            lo: 1,
            hi: 3
        }
    );
    assert_eq!(src.locate(f.span.start).0, 3);

    let (mut p, src) = plc("PROGRAM P
VAR i : INT; END_VAR
  WHILE TRUE DO i := i + 1; END_WHILE;
END_PROGRAM");
    p.set_budget(Budget(10_000));
    let f = p.scan(0, &mut words()).expect_err("the watchdog");
    assert_eq!(f.cause, FaultCause::Watchdog(10_000));
    assert_eq!(
        src.locate(f.span.start).0,
        3,
        "the watchdog's place: the loop"
    );
}

/// Each standard function in the interpreter, against values worked by hand.
#[test]
fn the_standard_functions() {
    let (mut p, _) = plc("PROGRAM P
VAR
  a, b, c, d, e, f, g : INT;
  r : REAL;
  w1, w2, w3, w4 : WORD;
  x : DINT;
  s : BOOL;
END_VAR
  a := ABS(-7);
  b := MIN(4, -2, 9);
  c := MAX(4, -2, 9);
  d := LIMIT(0, 120, 100);
  e := SEL(TRUE, 1, 2);
  f := MUX(2, 10, 20, 30);
  g := MOVE(5);
  r := SQRT(16.0);
  w1 := SHL(WORD#16#8001, 1);
  w2 := SHR(WORD#16#8001, 1);
  w3 := ROL(WORD#16#8001, 1);
  w4 := ROR(WORD#16#8001, 1);
  x := INT_TO_DINT(-3) * 100000;
  s := INT_TO_BOOL(2);
END_PROGRAM");
    p.scan(0, &mut words()).expect("a scan");
    let got: Vec<i64> = [
        "a", "b", "c", "d", "e", "f", "g", "w1", "w2", "w3", "w4", "x", "s",
    ]
    .iter()
    .map(|n| int(&p, n))
    .collect();
    assert_eq!(
        got,
        [7, -2, 9, 100, 2, 30, 5, 0x0002, 0x4000, 0x0003, 0xC000, -300_000, 1]
    );
    assert_eq!(real(&p, "r"), 4.0);
}

/// The watch list writes each value as a literal of its type, as a PLC's online mode shows it.
#[test]
fn the_watch_list_writes_each_value_as_a_literal_of_its_type() {
    let (mut p, _) = plc("PROGRAM w
VAR
  b : BOOL;
  w : WORD;
  bt : BYTE;
  i : INT;
  u : UDINT;
  r : REAL;
  t : TIME;
  z : TIME;
  n : TIME;
END_VAR
  b := TRUE;
  w := 16#BEEF;
  bt := 10;
  i := -12;
  u := 4000000000;
  r := 1.5;
  t := T#1d2h3m4s5ms;
  n := T#-1m30s;
END_PROGRAM");
    p.scan(0, &mut words()).expect("a scan");
    let shown: Vec<(String, String)> = p
        .watch_text()
        .into_iter()
        .map(|(n, v)| (n.to_owned(), v))
        .collect();
    let expect = [
        ("b", "TRUE"),
        ("w", "16#BEEF"),
        ("bt", "16#0A"),
        ("i", "-12"),
        ("u", "4000000000"),
        ("r", "1.5"),
        ("t", "T#1d2h3m4s5ms"),
        ("z", "T#0s"),
        ("n", "T#-1m30s"),
    ];
    for (name, text) in expect {
        assert!(
            shown.iter().any(|(n, v)| n == name && v == text),
            "{name} = {text} in {shown:?}"
        );
    }
}

/// A function named as an enumeration's value is called by its name, and inside it the name
/// is its result; elsewhere the bare name is the value.
#[test]
fn an_enumeration_value_does_not_hide_a_function_of_its_name() {
    let (mut p, _) = plc("TYPE Phase : (Idle, Ready); END_TYPE
FUNCTION Ready : BOOL
VAR_INPUT x : INT; END_VAR
  Ready := x > 2;
END_FUNCTION
PROGRAM P
VAR a, b : BOOL; s : Phase; END_VAR
  a := Ready(3);
  b := Ready(x := 1);
  s := Ready;
END_PROGRAM");
    p.scan(0, &mut words()).expect("a scan");
    let s = p.address("s").and_then(|a| p.read(a));
    assert_eq!(
        (int(&p, "a"), int(&p, "b"), s),
        (1, 0, Some(Value::Int(1))),
        "the calls give the function's results, the name alone the value"
    );
}

/// A bare value of two enumerations takes the one its context expects: assigned, compared,
/// passed to a function, a block's input, a CASE label, an initial value.
#[test]
fn a_value_of_two_enumerations_takes_the_expected_one() {
    let (mut p, _) = plc("TYPE
  Light : (Red, Amber, Green);
  Mood : (Calm, Green, Red);
END_TYPE
FUNCTION IsRed : BOOL
VAR_INPUT m : Mood; END_VAR
  IsRed := m = Red;
END_FUNCTION
FUNCTION_BLOCK Keep
VAR_INPUT m : Mood; END_VAR
VAR_OUTPUT out : Mood; END_VAR
  out := m;
END_FUNCTION_BLOCK
PROGRAM P
VAR
  l : Light := Green;
  m : Mood := Green;
  k : Keep;
  eq, ne, called, paren : BOOL;
  kept : Mood;
  arm : INT;
END_VAR
  m := Red;
  l := Red;
  eq := Red = m;
  ne := l <> (Green);
  called := IsRed(Red);
  k(m := Red);
  kept := k.out;
  paren := (m = (Red)) AND (Red = l);
  CASE m OF
    Calm: arm := 1;
    Red: arm := 3;
  ELSE
    arm := 9;
  END_CASE;
END_PROGRAM");
    let get = |p: &Plc, n: &str| p.address(n).and_then(|a| p.read(a));
    let n = |v: i64| Some(Value::Int(v));
    assert_eq!((get(&p, "l"), get(&p, "m")), (n(2), n(1)), "initial values");
    p.scan(0, &mut words()).expect("a scan");
    assert_eq!((get(&p, "m"), get(&p, "l")), (n(2), n(0)), "assigned");
    assert_eq!(
        (
            int(&p, "eq"),
            int(&p, "ne"),
            int(&p, "called"),
            int(&p, "paren")
        ),
        (1, 1, 1, 1),
        "compared, and passed to a function"
    );
    assert_eq!(get(&p, "kept"), n(2), "a block's input");
    assert_eq!(int(&p, "arm"), 3, "a CASE label");
}
