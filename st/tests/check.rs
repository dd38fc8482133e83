//! The declarations checked: a program with every kind of declaration resolves as declared,
//! and a corpus of wrong declarations gets its messages (snapshots).

use st::ast::VarKind;
use st::check::{check, Checked, Location, StdFb, Type};
use st::parser::parse;
use st::source::Source;
use st::types::Elem;

fn checked(text: &str) -> (Checked, String) {
    let src = Source::new("decl.st", text);
    let (unit, errors) = parse(&src);
    assert!(errors.is_empty(), "{}", src.render_all(&errors));
    let (c, errors) = check(&unit);
    (c, src.render_all(&errors))
}

const DECLARATIONS: &str = r#"
TYPE
    Dir : (Stop, Up := 5, Down);
    Floor : INT (1..4);
    Station : STRUCT
        call : BOOL;
        shown : WORD;
        timer : TON;
    END_STRUCT;
    Stations : ARRAY [1..FLOORS] OF Station;
END_TYPE

VAR_GLOBAL CONSTANT
    FLOORS : INT := 2 * 2;
END_VAR

FUNCTION_BLOCK Door
VAR_INPUT open : BOOL; END_VAR
VAR t : TOF; edge : R_TRIG; END_VAR
END_FUNCTION_BLOCK

FUNCTION Twice : DINT
VAR_INPUT x : INT; END_VAR
    Twice := x * 2;
END_FUNCTION

PROGRAM Lift
VAR
    d1 AT %IX2.3 : BOOL;
    speed AT %QW68 : WORD;
    run AT %QX3.12 : BOOL;
    here : Floor := 1;
    dir : Dir;
    stations : Stations;
    doors : ARRAY [0..1, 1..3] OF Door;
    t : TIME := T#1s;
END_VAR
END_PROGRAM
"#;

#[test]
fn declarations_resolve_as_declared() {
    let (c, errors) = checked(DECLARATIONS);
    assert_eq!(errors, "");
    let lift = c.program().expect("the program");
    let var = |n: &str| lift.vars.iter().find(|v| v.name == n).expect(n);
    assert_eq!(var("d1").at, Some(Location::InputBit(2, 3)));
    assert_eq!(var("speed").at, Some(Location::OutputWord(68)));
    assert_eq!(var("run").at, Some(Location::OutputBit(3, 12)));
    assert_eq!(var("here").ty, Type::Subrange(Elem::Int, 1, 4));
    assert_eq!(var("t").ty, Type::Elem(Elem::Time));
    assert_eq!(var("here").kind, VarKind::Local);
    let Type::Enum(dir) = var("dir").ty else {
        panic!("an enumeration")
    };
    let values: Vec<(&str, i128)> = c.enums[dir]
        .values
        .iter()
        .map(|(k, n)| (k.as_str(), *n))
        .collect();
    assert_eq!(values, [("STOP", 0), ("UP", 5), ("DOWN", 6)]);
    let Type::Array(stations) = &var("stations").ty else {
        panic!("an array")
    };
    assert_eq!(stations.dims, [(1, 4)]);
    let Type::Struct(station) = stations.elem else {
        panic!("of structures")
    };
    assert_eq!(c.structs[station].fields[2].ty, Type::StdFb(StdFb::Ton));
    // 4 stations of 3, 6 doors of an input and two blocks.
    assert_eq!(c.elements(&var("stations").ty), 12);
    assert_eq!(c.elements(&var("doors").ty), 18);
    let twice = c
        .pous
        .iter()
        .find(|p| p.name == "Twice")
        .expect("the function");
    assert_eq!(twice.result, Some(Type::Elem(Elem::Dint)));
}

#[test]
fn wrong_declarations_get_their_messages() {
    let corpus: &[(&str, &str)] = &[
        (
            "names",
            "TYPE INT : WORD; END_TYPE\nTYPE A : BOOL; A : WORD; END_TYPE\nFUNCTION_BLOCK TON END_FUNCTION_BLOCK\nPROGRAM P\nVAR x : BOOL; x : INT; y : Nothing; s : STRING; f : Twice; END_VAR\nEND_PROGRAM\nFUNCTION Twice : INT END_FUNCTION\n",
        ),
        (
            "locations",
            "PROGRAM P\nVAR\n  a AT %IW300 : WORD;\n  b AT %IX1.16 : BOOL;\n  c AT %QX0.1 : INT;\n  d AT %MW3 : WORD;\n  e AT %IB2 : BYTE;\n  f AT %IX4 : BOOL;\n  g, h AT %QW1 : WORD;\nEND_VAR\nEND_PROGRAM\nFUNCTION_BLOCK B\nVAR_INPUT i AT %IX0.0 : BOOL; END_VAR\nEND_FUNCTION_BLOCK\n",
        ),
        (
            "sizes_and_cycles",
            "TYPE S : STRUCT inner : S; END_STRUCT; END_TYPE\nFUNCTION_BLOCK A VAR b : B; END_VAR END_FUNCTION_BLOCK\nFUNCTION_BLOCK B VAR a : ARRAY [1..2] OF A; END_VAR END_FUNCTION_BLOCK\nFUNCTION F : INT VAR t : TON; END_VAR END_FUNCTION\nPROGRAM P\nVAR\n  huge : ARRAY [1..100000, 1..100000] OF BOOL;\n  empty : ARRAY [3..1] OF INT;\n  r : SINT (0..200);\n  z : ARRAY [1..10 / 0] OF INT;\n  n : ARRAY [1..N] OF INT;\nEND_VAR\nEND_PROGRAM\n",
        ),
        (
            "programs",
            "PROGRAM A END_PROGRAM\nPROGRAM B END_PROGRAM\n",
        ),
        ("no_program", "FUNCTION_BLOCK B END_FUNCTION_BLOCK\n"),
        (
            "in_out",
            "FUNCTION_BLOCK B VAR_IN_OUT x : INT; END_VAR END_FUNCTION_BLOCK\nPROGRAM P END_PROGRAM\n",
        ),
    ];
    for (name, text) in corpus {
        let (_, errors) = checked(text);
        insta::assert_snapshot!(*name, errors);
    }
}
