//! Structured Text's grammar (IEC 61131-3, 3rd edition, §6 and §7.3), by recursive descent.
//!
//! Every error is reported at its place and the parser goes on after it (at the next `;`, or
//! at the keyword that ends the block it is in), so that a program's errors come all at once,
//! as a PLC programmer's compiler gives them. Nesting is bounded ([`MAX_NESTING`]): a hostile
//! source gets an error, never a stack overflow.

use crate::ast::*;
use crate::lexer::{lex, Kw, Size, Sym, Tok, Token};
use crate::source::{Diagnostic, Source, Span, MAX_ERRORS, MAX_SOURCE_BYTES};

/// How deep statements and expressions may nest: far beyond any program a person writes.
pub const MAX_NESTING: u32 = 64;

/// The declarations of `src`, and every error found in it (none: the source is well formed).
pub fn parse(src: &Source) -> (Unit, Vec<Diagnostic>) {
    if src.text().len() > MAX_SOURCE_BYTES {
        let d = Diagnostic::error(
            Span::new(0, 0),
            format!(
                "the file has {} bytes: more than the {MAX_SOURCE_BYTES} a program may have",
                src.text().len()
            ),
        );
        return (Unit::default(), vec![d]);
    }
    // Each file on its own (a comment or a block left open in one does not run into the
    // next), its places shifted to where it lies in the whole text.
    let mut unit = Unit::default();
    let mut errors = Vec::new();
    for (_, range) in src.file_ranges() {
        let base = range.start;
        let (mut toks, lex_errors) = lex(&src.text()[range]);
        let shift = |s: &mut Span| {
            *s = Span::new(s.start as usize + base, s.end as usize + base);
        };
        for t in &mut toks {
            shift(&mut t.span);
        }
        let mut p = Parser {
            src,
            toks,
            pos: 0,
            errors: lex_errors,
            depth: 0,
        };
        for d in &mut p.errors {
            shift(&mut d.span);
        }
        unit.items.extend(p.unit().items);
        errors.append(&mut p.errors);
    }
    errors.sort_by_key(|d| d.span.start);
    if errors.len() > MAX_ERRORS {
        let more = errors.len() - MAX_ERRORS;
        errors.truncate(MAX_ERRORS);
        let at = errors.last().map_or(Span::default(), |d| d.span);
        errors.push(Diagnostic::error(
            at,
            format!("{more} more errors after this one are not shown"),
        ));
    }
    (unit, errors)
}

struct Parser<'a> {
    src: &'a Source,
    toks: Vec<Token>,
    pos: usize,
    errors: Vec<Diagnostic>,
    depth: u32,
}

/// The keywords that end a statement list: the parser does not skip past them to recover.
fn ends_block(k: Kw) -> bool {
    matches!(
        k,
        Kw::EndProgram
            | Kw::EndFunction
            | Kw::EndFunctionBlock
            | Kw::EndIf
            | Kw::Elsif
            | Kw::Else
            | Kw::EndCase
            | Kw::EndFor
            | Kw::EndWhile
            | Kw::Until
            | Kw::EndRepeat
            | Kw::EndVar
            | Kw::EndType
            | Kw::EndStruct
            | Kw::Program
            | Kw::Function
            | Kw::FunctionBlock
            | Kw::Type
            | Kw::VarGlobal
    )
}

impl Parser<'_> {
    fn tok(&self) -> &Tok {
        &self.toks[self.pos.min(self.toks.len() - 1)].tok
    }

    fn tok_at(&self, k: usize) -> &Tok {
        &self.toks[(self.pos + k).min(self.toks.len() - 1)].tok
    }

    fn span(&self) -> Span {
        self.toks[self.pos.min(self.toks.len() - 1)].span
    }

    /// The place just after the last token taken.
    fn prev_end(&self) -> Span {
        let s = self.toks[self.pos.saturating_sub(1)].span;
        Span {
            start: s.end,
            end: s.end,
        }
    }

    fn bump(&mut self) -> Span {
        let s = self.span();
        if self.pos < self.toks.len() - 1 {
            self.pos += 1;
        }
        s
    }

    fn at_kw(&self, k: Kw) -> bool {
        *self.tok() == Tok::Kw(k)
    }

    fn at_sym(&self, s: Sym) -> bool {
        *self.tok() == Tok::Sym(s)
    }

    fn eat_kw(&mut self, k: Kw) -> Option<Span> {
        self.at_kw(k).then(|| self.bump())
    }

    fn eat_sym(&mut self, s: Sym) -> Option<Span> {
        self.at_sym(s).then(|| self.bump())
    }

    fn error(&mut self, span: Span, message: impl Into<String>) {
        let message = message.into();
        // The same error twice at one place says nothing new.
        if self
            .errors
            .last()
            .is_some_and(|d| d.span == span && d.message == message)
        {
            return;
        }
        self.errors.push(Diagnostic::error(span, message));
    }

    /// An error at the present token: `expected`, found what is there.
    fn expected(&mut self, expected: &str) {
        let found = self.tok().describe();
        let span = if *self.tok() == Tok::Eof {
            self.prev_end()
        } else {
            self.span()
        };
        self.error(span, format!("expected {expected}, found {found}"));
    }

    fn expect_kw(&mut self, k: Kw) -> Option<Span> {
        let s = self.eat_kw(k);
        if s.is_none() {
            self.expected(&format!("`{}`", k.text()));
        }
        s
    }

    /// The keyword `end` that closes the block opened by `open` at `opened`.
    fn close(&mut self, end: Kw, open: Kw, opened: Span) -> Option<Span> {
        let s = self.eat_kw(end);
        if s.is_none() {
            let found = self.tok().describe();
            let span = if *self.tok() == Tok::Eof {
                self.prev_end()
            } else {
                self.span()
            };
            let (line, column, _) = self.src.locate(opened.start);
            self.error(
                span,
                format!(
                    "expected `{}` to close the {} at {line}:{column}, found {found}",
                    end.text(),
                    open.text(),
                ),
            );
        }
        s
    }

    fn expect_sym(&mut self, s: Sym) -> Option<Span> {
        let got = self.eat_sym(s);
        if got.is_none() {
            self.expected(&format!("`{}`", s.text()));
        }
        got
    }

    fn ident(&mut self) -> Option<Ident> {
        if let Tok::Ident(text) = self.tok() {
            let text = text.clone();
            let span = self.bump();
            return Some(Ident { text, span });
        }
        None
    }

    fn expect_ident(&mut self, what: &str) -> Option<Ident> {
        let i = self.ident();
        if i.is_none() {
            self.expected(what);
        }
        i
    }

    /// Skips to just after the next `;`, or to a keyword that ends a block.
    fn sync(&mut self) {
        loop {
            match self.tok() {
                Tok::Eof => return,
                Tok::Sym(Sym::Semi) => {
                    self.bump();
                    return;
                }
                Tok::Kw(k) if ends_block(*k) => return,
                _ => {
                    self.bump();
                }
            }
        }
    }

    /// Enters one more level of nesting; `false` (reported) if that is too deep.
    fn enter(&mut self) -> bool {
        self.depth += 1;
        if self.depth > MAX_NESTING {
            let span = self.span();
            self.error(
                span,
                format!("nested more than {MAX_NESTING} deep: simplify the program here"),
            );
            return false;
        }
        true
    }

    fn leave(&mut self) {
        self.depth -= 1;
    }

    // ----- declarations ---------------------------------------------------------------

    fn unit(&mut self) -> Unit {
        let mut items = Vec::new();
        loop {
            match self.tok().clone() {
                Tok::Eof => break,
                Tok::Kw(Kw::Type) => items.push(Item::Types(self.types())),
                Tok::Kw(Kw::VarGlobal) => {
                    if let Some(b) = self.var_block() {
                        items.push(Item::Globals(b));
                    }
                }
                Tok::Kw(Kw::Program | Kw::Function | Kw::FunctionBlock) => {
                    if let Some(p) = self.pou() {
                        items.push(Item::Pou(Box::new(p)));
                    }
                }
                _ => {
                    self.expected("PROGRAM, FUNCTION, FUNCTION_BLOCK, TYPE or VAR_GLOBAL");
                    // On to the next declaration.
                    self.bump();
                    while !matches!(
                        self.tok(),
                        Tok::Eof
                            | Tok::Kw(
                                Kw::Type
                                    | Kw::VarGlobal
                                    | Kw::Program
                                    | Kw::Function
                                    | Kw::FunctionBlock
                            )
                    ) {
                        self.bump();
                    }
                }
            }
        }
        Unit { items }
    }

    fn types(&mut self) -> Vec<TypeDecl> {
        self.bump();
        let mut out = Vec::new();
        while !matches!(self.tok(), Tok::Eof | Tok::Kw(Kw::EndType)) {
            if matches!(self.tok(), Tok::Kw(k) if ends_block(*k)) {
                break;
            }
            let start = self.span();
            let Some(name) = self.expect_ident("a type's name") else {
                self.sync();
                continue;
            };
            if self.expect_sym(Sym::Colon).is_none() {
                self.sync();
                continue;
            }
            let Some(ty) = self.type_ref(true) else {
                self.sync();
                continue;
            };
            let init = if self.eat_sym(Sym::Assign).is_some() {
                self.init()
            } else {
                None
            };
            let end = self.expect_sym(Sym::Semi);
            if end.is_none() {
                self.sync();
            }
            out.push(TypeDecl {
                name,
                ty,
                init,
                span: start.to(self.prev_end()),
            });
        }
        self.expect_kw(Kw::EndType);
        out
    }

    fn var_kind(&self) -> Option<VarKind> {
        Some(match self.tok() {
            Tok::Kw(Kw::Var) => VarKind::Local,
            Tok::Kw(Kw::VarInput) => VarKind::Input,
            Tok::Kw(Kw::VarOutput) => VarKind::Output,
            Tok::Kw(Kw::VarInOut) => VarKind::InOut,
            Tok::Kw(Kw::VarTemp) => VarKind::Temp,
            Tok::Kw(Kw::VarGlobal) => VarKind::Global,
            Tok::Kw(Kw::VarExternal) => VarKind::External,
            _ => return None,
        })
    }

    fn var_block(&mut self) -> Option<VarBlock> {
        let kind = self.var_kind()?;
        let start = self.bump();
        let mut constant = false;
        let mut retain = false;
        loop {
            if self.eat_kw(Kw::Constant).is_some() {
                constant = true;
            } else if self.eat_kw(Kw::Retain).is_some() {
                retain = true;
            } else if self.eat_kw(Kw::NonRetain).is_none() {
                break;
            }
        }
        let mut decls = Vec::new();
        while matches!(self.tok(), Tok::Ident(_)) {
            if let Some(d) = self.var_decl(false) {
                decls.push(d);
            }
        }
        let end = self
            .expect_kw(Kw::EndVar)
            .unwrap_or_else(|| self.prev_end());
        Some(VarBlock {
            kind,
            constant,
            retain,
            decls,
            span: start.to(end),
        })
    }

    /// `a, b AT %… : type := init;` (`in_struct`: a structure's field, which has no `AT`).
    fn var_decl(&mut self, in_struct: bool) -> Option<VarDecl> {
        let start = self.span();
        let mut names = Vec::new();
        loop {
            match self.expect_ident("a variable's name") {
                Some(i) => names.push(i),
                None => {
                    self.sync();
                    return None;
                }
            }
            if self.eat_sym(Sym::Comma).is_none() {
                break;
            }
        }
        let mut at = None;
        if !in_struct && self.eat_kw(Kw::At).is_some() {
            match self.tok().clone() {
                Tok::Direct(d) => {
                    let s = self.bump();
                    at = Some((d, s));
                }
                _ => {
                    self.expected("a direct variable after AT (e.g. %IX2.3)");
                    self.sync();
                    return None;
                }
            }
        }
        if self.expect_sym(Sym::Colon).is_none() {
            self.sync();
            return None;
        }
        let Some(ty) = self.type_ref(false) else {
            self.sync();
            return None;
        };
        let init = if self.eat_sym(Sym::Assign).is_some() {
            self.init()
        } else {
            None
        };
        if self.expect_sym(Sym::Semi).is_none() {
            self.sync();
        }
        Some(VarDecl {
            names,
            at,
            ty,
            init,
            span: start.to(self.prev_end()),
        })
    }

    /// A type: a name, a subrange, an array, an enumeration in place, or (`in_type`: in a
    /// `TYPE` block) a structure.
    fn type_ref(&mut self, in_type: bool) -> Option<TypeRef> {
        let start = self.span();
        match self.tok().clone() {
            Tok::Kw(Kw::Array) => {
                self.bump();
                self.expect_sym(Sym::LBracket)?;
                let mut dims = Vec::new();
                loop {
                    let lo = self.expr()?;
                    self.expect_sym(Sym::DotDot)?;
                    let hi = self.expr()?;
                    dims.push((lo, hi));
                    if self.eat_sym(Sym::Comma).is_none() {
                        break;
                    }
                }
                self.expect_sym(Sym::RBracket)?;
                self.expect_kw(Kw::Of)?;
                if !self.enter() {
                    self.leave();
                    return None;
                }
                let elem = self.type_ref(false);
                self.leave();
                let elem = elem?;
                Some(TypeRef::Array {
                    dims,
                    elem: Box::new(elem),
                    span: start.to(self.prev_end()),
                })
            }
            Tok::Kw(Kw::Struct) if in_type => {
                self.bump();
                let mut fields = Vec::new();
                while matches!(self.tok(), Tok::Ident(_)) {
                    if let Some(d) = self.var_decl(true) {
                        fields.push(d);
                    }
                }
                self.expect_kw(Kw::EndStruct)?;
                Some(TypeRef::Struct {
                    fields,
                    span: start.to(self.prev_end()),
                })
            }
            Tok::Sym(Sym::LParen) => {
                self.bump();
                let mut values = Vec::new();
                loop {
                    let name = self.expect_ident("an enumeration value")?;
                    let value = if self.eat_sym(Sym::Assign).is_some() {
                        Some(self.expr()?)
                    } else {
                        None
                    };
                    values.push((name, value));
                    if self.eat_sym(Sym::Comma).is_none() {
                        break;
                    }
                }
                self.expect_sym(Sym::RParen)?;
                Some(TypeRef::Enum {
                    values,
                    span: start.to(self.prev_end()),
                })
            }
            Tok::Ident(_) => {
                let base = self.ident()?;
                if self.eat_sym(Sym::LParen).is_some() {
                    let lo = self.expr()?;
                    self.expect_sym(Sym::DotDot)?;
                    let hi = self.expr()?;
                    self.expect_sym(Sym::RParen)?;
                    return Some(TypeRef::Subrange {
                        base,
                        lo,
                        hi,
                        span: start.to(self.prev_end()),
                    });
                }
                Some(TypeRef::Named(base))
            }
            _ => {
                self.expected("a type");
                None
            }
        }
    }

    /// An initial value: an expression, `[…]` for an array, `(f := …)` for a structure.
    fn init(&mut self) -> Option<Init> {
        let start = self.span();
        if self.at_sym(Sym::LBracket) {
            self.bump();
            let mut elems = Vec::new();
            if !self.at_sym(Sym::RBracket) {
                loop {
                    // `n(value)`: value n times.
                    let repeated = matches!(self.tok(), Tok::Int(_))
                        && *self.tok_at(1) == Tok::Sym(Sym::LParen);
                    if repeated {
                        let n = self.primary()?;
                        self.expect_sym(Sym::LParen)?;
                        let v = if self.at_sym(Sym::RParen) {
                            None
                        } else {
                            self.init()
                        };
                        self.expect_sym(Sym::RParen)?;
                        let v = v.unwrap_or(Init::Array(Vec::new(), self.prev_end()));
                        elems.push((Some(n), v));
                    } else {
                        elems.push((None, self.init()?));
                    }
                    if self.eat_sym(Sym::Comma).is_none() {
                        break;
                    }
                }
            }
            self.expect_sym(Sym::RBracket)?;
            return Some(Init::Array(elems, start.to(self.prev_end())));
        }
        let is_struct = self.at_sym(Sym::LParen)
            && matches!(self.tok_at(1), Tok::Ident(_))
            && *self.tok_at(2) == Tok::Sym(Sym::Assign);
        if is_struct {
            self.bump();
            let mut fields = Vec::new();
            loop {
                let name = self.expect_ident("a field's name")?;
                self.expect_sym(Sym::Assign)?;
                fields.push((name, self.init()?));
                if self.eat_sym(Sym::Comma).is_none() {
                    break;
                }
            }
            self.expect_sym(Sym::RParen)?;
            return Some(Init::Struct(fields, start.to(self.prev_end())));
        }
        self.expr().map(Init::Expr)
    }

    fn pou(&mut self) -> Option<Pou> {
        let start = self.span();
        let (end_kw, kind_kw) = match self.tok() {
            Tok::Kw(Kw::Program) => (Kw::EndProgram, Kw::Program),
            Tok::Kw(Kw::Function) => (Kw::EndFunction, Kw::Function),
            _ => (Kw::EndFunctionBlock, Kw::FunctionBlock),
        };
        self.bump();
        let name = match self.expect_ident("a name") {
            Some(n) => n,
            None => Ident {
                text: String::new(),
                span: self.span(),
            },
        };
        let kind = match kind_kw {
            Kw::Program => PouKind::Program,
            Kw::FunctionBlock => PouKind::FunctionBlock,
            _ => {
                let ty = if self.expect_sym(Sym::Colon).is_some() {
                    self.type_ref(false)
                } else {
                    None
                };
                PouKind::Function(ty.unwrap_or_else(|| {
                    TypeRef::Named(Ident {
                        text: "INT".into(),
                        span: name.span,
                    })
                }))
            }
        };
        let mut vars = Vec::new();
        while self.var_kind().is_some() {
            if let Some(b) = self.var_block() {
                vars.push(b);
            }
        }
        let body = self.stmts();
        if self.close(end_kw, kind_kw, start).is_none() {
            // A stray block end: skip it and what follows to the unit's end.
            while !matches!(
                self.tok(),
                Tok::Eof
                    | Tok::Kw(
                        Kw::Type | Kw::Program | Kw::Function | Kw::FunctionBlock | Kw::VarGlobal
                    )
            ) && !self.at_kw(end_kw)
            {
                self.bump();
            }
            self.eat_kw(end_kw);
        }
        Some(Pou {
            kind,
            name,
            vars,
            body,
            span: start.to(self.prev_end()),
        })
    }

    // ----- statements -----------------------------------------------------------------

    /// Statements up to a keyword that ends a block (not taken).
    fn stmts(&mut self) -> Vec<Stmt> {
        let mut out = Vec::new();
        loop {
            match self.tok() {
                Tok::Eof => break,
                Tok::Kw(k) if ends_block(*k) => break,
                _ => {}
            }
            let before = self.pos;
            if let Some(s) = self.stmt() {
                out.push(s);
            }
            if self.pos == before {
                // Nothing taken: skip the token, or the loop would not end.
                self.bump();
            }
        }
        out
    }

    /// A statement and its `;`.
    fn stmt(&mut self) -> Option<Stmt> {
        let start = self.span();
        if !self.enter() {
            self.leave();
            self.sync();
            return None;
        }
        let kind = self.stmt_kind();
        self.leave();
        let Some(kind) = kind else {
            self.sync();
            return None;
        };
        if kind != StmtKind::Empty && self.eat_sym(Sym::Semi).is_none() {
            let span = self.prev_end();
            self.error(span, "`;` is missing after this statement");
            // Take nothing more: the next statement may start right here.
        }
        Some(Stmt {
            kind,
            span: start.to(self.prev_end()),
        })
    }

    fn stmt_kind(&mut self) -> Option<StmtKind> {
        match self.tok().clone() {
            Tok::Sym(Sym::Semi) => {
                self.bump();
                Some(StmtKind::Empty)
            }
            Tok::Kw(Kw::If) => self.if_stmt(),
            Tok::Kw(Kw::Case) => self.case_stmt(),
            Tok::Kw(Kw::For) => self.for_stmt(),
            Tok::Kw(Kw::While) => {
                let opened = self.bump();
                let cond = self.expr()?;
                self.expect_kw(Kw::Do)?;
                let body = self.stmts();
                self.close(Kw::EndWhile, Kw::While, opened)?;
                Some(StmtKind::While { cond, body })
            }
            Tok::Kw(Kw::Repeat) => {
                let opened = self.bump();
                let body = self.stmts();
                self.close(Kw::Until, Kw::Repeat, opened)?;
                let until = self.expr()?;
                self.close(Kw::EndRepeat, Kw::Repeat, opened)?;
                Some(StmtKind::Repeat { body, until })
            }
            Tok::Kw(Kw::Exit) => {
                self.bump();
                Some(StmtKind::Exit)
            }
            Tok::Kw(Kw::Continue) => {
                self.bump();
                Some(StmtKind::Continue)
            }
            Tok::Kw(Kw::Return) => {
                self.bump();
                Some(StmtKind::Return)
            }
            Tok::Ident(_) | Tok::Direct(_) => {
                let target = self.postfix()?;
                if self.eat_sym(Sym::Assign).is_some() {
                    let value = self.expr()?;
                    return Some(StmtKind::Assign { target, value });
                }
                if matches!(target.kind, ExprKind::Call(..)) {
                    return Some(StmtKind::Call(target));
                }
                if self.at_sym(Sym::Eq) {
                    self.error(
                        self.span(),
                        "`=` compares; an assignment is written `:=`".to_owned(),
                    );
                    return None;
                }
                self.expected("`:=` or a call's `(`");
                None
            }
            _ => {
                self.expected("a statement");
                None
            }
        }
    }

    fn if_stmt(&mut self) -> Option<StmtKind> {
        let opened = self.bump();
        let mut arms = Vec::new();
        let cond = self.expr()?;
        self.expect_kw(Kw::Then)?;
        arms.push((cond, self.stmts()));
        let mut otherwise = Vec::new();
        loop {
            if self.eat_kw(Kw::Elsif).is_some() {
                let cond = self.expr()?;
                self.expect_kw(Kw::Then)?;
                arms.push((cond, self.stmts()));
            } else if self.eat_kw(Kw::Else).is_some() {
                otherwise = self.stmts();
            } else {
                break;
            }
        }
        self.close(Kw::EndIf, Kw::If, opened)?;
        Some(StmtKind::If { arms, otherwise })
    }

    fn case_stmt(&mut self) -> Option<StmtKind> {
        let opened = self.bump();
        let selector = self.expr()?;
        self.expect_kw(Kw::Of)?;
        let mut arms: Vec<(Vec<CaseLabel>, Vec<Stmt>)> = Vec::new();
        let mut otherwise = Vec::new();
        loop {
            match self.tok() {
                Tok::Kw(Kw::EndCase) | Tok::Eof => break,
                Tok::Kw(Kw::Else) => {
                    self.bump();
                    otherwise = self.stmts();
                    break;
                }
                Tok::Kw(k) if ends_block(*k) => break,
                _ => {}
            }
            let Some(labels) = self.case_labels() else {
                self.expected("a CASE label (a value or a range, then `:`)");
                self.sync();
                continue;
            };
            // The arm's statements, up to the next label.
            let mut body = Vec::new();
            loop {
                match self.tok() {
                    Tok::Eof => break,
                    Tok::Kw(k) if ends_block(*k) => break,
                    _ => {}
                }
                if self.looks_like_labels() {
                    break;
                }
                let before = self.pos;
                if let Some(s) = self.stmt() {
                    body.push(s);
                }
                if self.pos == before {
                    self.bump();
                }
            }
            arms.push((labels, body));
        }
        self.close(Kw::EndCase, Kw::Case, opened)?;
        Some(StmtKind::Case {
            selector,
            arms,
            otherwise,
        })
    }

    /// `true` if CASE labels and their `:` come next (tried, then undone).
    fn looks_like_labels(&mut self) -> bool {
        let (pos, errors) = (self.pos, self.errors.len());
        let found = self.case_labels().is_some();
        self.pos = pos;
        self.errors.truncate(errors);
        found
    }

    /// `label, label, …:` where a label is a value or `lo..hi`; `None` (nothing taken, no
    /// error) if those do not come next.
    fn case_labels(&mut self) -> Option<Vec<CaseLabel>> {
        let (pos, errors) = (self.pos, self.errors.len());
        let mut labels = Vec::new();
        let ok = loop {
            let Some(lo) = self.expr() else {
                break false;
            };
            if self.eat_sym(Sym::DotDot).is_some() {
                let Some(hi) = self.expr() else {
                    break false;
                };
                labels.push(CaseLabel::Range(lo, hi));
            } else {
                labels.push(CaseLabel::Value(lo));
            }
            if self.eat_sym(Sym::Comma).is_none() {
                break self.eat_sym(Sym::Colon).is_some();
            }
        };
        if !ok {
            self.pos = pos;
            self.errors.truncate(errors);
            return None;
        }
        Some(labels)
    }

    fn for_stmt(&mut self) -> Option<StmtKind> {
        let opened = self.bump();
        let var = self.expect_ident("the FOR loop's variable")?;
        self.expect_sym(Sym::Assign)?;
        let from = self.expr()?;
        self.expect_kw(Kw::To)?;
        let to = self.expr()?;
        let by = if self.eat_kw(Kw::By).is_some() {
            Some(self.expr()?)
        } else {
            None
        };
        self.expect_kw(Kw::Do)?;
        let body = self.stmts();
        self.close(Kw::EndFor, Kw::For, opened)?;
        Some(StmtKind::For {
            var,
            from,
            to,
            by,
            body,
        })
    }

    // ----- expressions ----------------------------------------------------------------

    /// `true` if the present token can start an operand.
    fn starts_operand(&self) -> bool {
        matches!(
            self.tok(),
            Tok::Int(_)
                | Tok::Real(_)
                | Tok::Time(_)
                | Tok::Str(_)
                | Tok::Direct(_)
                | Tok::Ident(_)
                | Tok::Bad
                | Tok::Kw(Kw::True | Kw::False | Kw::Not)
                | Tok::Sym(Sym::LParen | Sym::Minus | Sym::Plus)
        )
    }

    /// An expression, weakest operator first (table 71 of IEC 61131-3, 3rd edition).
    fn expr(&mut self) -> Option<Expr> {
        if !self.enter() {
            self.leave();
            return None;
        }
        let e = self.binary(0);
        self.leave();
        e
    }

    /// The operators of precedence level `level` (0: OR … 6: `*`, `/`, MOD) and stronger.
    fn binary(&mut self, level: u8) -> Option<Expr> {
        if level > 6 {
            return self.unary();
        }
        let mut left = self.binary(level + 1)?;
        loop {
            let op = match (level, self.tok()) {
                (0, Tok::Kw(Kw::Or)) => BinOp::Or,
                (1, Tok::Kw(Kw::Xor)) => BinOp::Xor,
                (2, Tok::Kw(Kw::And)) | (2, Tok::Sym(Sym::Amp)) => BinOp::And,
                (3, Tok::Sym(Sym::Eq)) => BinOp::Eq,
                (3, Tok::Sym(Sym::Ne)) => BinOp::Ne,
                (4, Tok::Sym(Sym::Lt)) => BinOp::Lt,
                (4, Tok::Sym(Sym::Gt)) => BinOp::Gt,
                (4, Tok::Sym(Sym::Le)) => BinOp::Le,
                (4, Tok::Sym(Sym::Ge)) => BinOp::Ge,
                (5, Tok::Sym(Sym::Plus)) => BinOp::Add,
                (5, Tok::Sym(Sym::Minus)) => BinOp::Sub,
                (6, Tok::Sym(Sym::Star)) => BinOp::Mul,
                (6, Tok::Sym(Sym::Slash)) => BinOp::Div,
                (6, Tok::Kw(Kw::Mod)) => BinOp::Mod,
                _ => return Some(left),
            };
            let op_span = self.bump();
            if !self.starts_operand() {
                self.error(
                    op_span,
                    format!("an operand is missing after `{}`", op.text()),
                );
                return None;
            }
            let right = self.binary(level + 1)?;
            let span = left.span.to(right.span);
            left = Expr {
                kind: ExprKind::Binary(op, Box::new(left), Box::new(right)),
                span,
            };
        }
    }

    /// `-`, `+`, `NOT`, then `**` (which binds stronger: `-2**2` is −4).
    fn unary(&mut self) -> Option<Expr> {
        let start = self.span();
        let op = match self.tok() {
            Tok::Sym(Sym::Minus) => Some(UnOp::Neg),
            Tok::Sym(Sym::Plus) => Some(UnOp::Plus),
            Tok::Kw(Kw::Not) => Some(UnOp::Not),
            _ => None,
        };
        if let Some(op) = op {
            self.bump();
            if !self.enter() {
                self.leave();
                return None;
            }
            let operand = self.unary();
            self.leave();
            let operand = operand?;
            let span = start.to(operand.span);
            return Some(Expr {
                kind: ExprKind::Unary(op, Box::new(operand)),
                span,
            });
        }
        let mut left = self.postfix()?;
        while self.at_sym(Sym::Power) {
            let op_span = self.bump();
            if !self.starts_operand() {
                self.error(op_span, "an operand is missing after `**`");
                return None;
            }
            let right = self.unary_operand()?;
            let span = left.span.to(right.span);
            left = Expr {
                kind: ExprKind::Binary(BinOp::Power, Box::new(left), Box::new(right)),
                span,
            };
        }
        Some(left)
    }

    /// The right operand of `**`: a sign is allowed (`2 ** -1`).
    fn unary_operand(&mut self) -> Option<Expr> {
        let start = self.span();
        if self.at_sym(Sym::Minus) {
            self.bump();
            let e = self.postfix()?;
            let span = start.to(e.span);
            return Some(Expr {
                kind: ExprKind::Unary(UnOp::Neg, Box::new(e)),
                span,
            });
        }
        self.postfix()
    }

    /// A primary with its fields, bits, indices and calls.
    fn postfix(&mut self) -> Option<Expr> {
        let mut e = self.primary()?;
        loop {
            if self.at_sym(Sym::Dot) {
                self.bump();
                match self.tok().clone() {
                    Tok::Ident(_) => {
                        let f = self.ident()?;
                        let span = e.span.to(f.span);
                        e = Expr {
                            kind: ExprKind::Field(Box::new(e), f),
                            span,
                        };
                    }
                    Tok::Int(n) => {
                        let s = self.bump();
                        let Ok(n) = u32::try_from(n) else {
                            self.error(s, "no bit string has that many bits");
                            return None;
                        };
                        let span = e.span.to(s);
                        e = Expr {
                            kind: ExprKind::Bit(Box::new(e), n),
                            span,
                        };
                    }
                    Tok::Partial(Size::Bit, n) => {
                        let s = self.bump();
                        let span = e.span.to(s);
                        e = Expr {
                            kind: ExprKind::Bit(Box::new(e), n),
                            span,
                        };
                    }
                    Tok::Partial(..) => {
                        let s = self.bump();
                        self.error(
                            s,
                            "only bit access (`.%Xn`) is supported, not a byte's or a word's",
                        );
                        return None;
                    }
                    _ => {
                        self.expected("a field's name or a bit's number after `.`");
                        return None;
                    }
                }
            } else if self.at_sym(Sym::LBracket) {
                self.bump();
                let mut idx = vec![self.expr()?];
                while self.eat_sym(Sym::Comma).is_some() {
                    idx.push(self.expr()?);
                }
                let end = self.expect_sym(Sym::RBracket)?;
                let span = e.span.to(end);
                e = Expr {
                    kind: ExprKind::Index(Box::new(e), idx),
                    span,
                };
            } else if self.at_sym(Sym::LParen)
                && matches!(
                    e.kind,
                    ExprKind::Name(_) | ExprKind::Field(..) | ExprKind::Index(..)
                )
            {
                self.bump();
                let args = self.args()?;
                let end = self.expect_sym(Sym::RParen)?;
                let span = e.span.to(end);
                e = Expr {
                    kind: ExprKind::Call(Box::new(e), args),
                    span,
                };
            } else {
                return Some(e);
            }
        }
    }

    /// A call's arguments, up to (not taking) its `)`.
    fn args(&mut self) -> Option<Vec<Arg>> {
        let mut args = Vec::new();
        if self.at_sym(Sym::RParen) {
            return Some(args);
        }
        loop {
            let named = matches!(self.tok(), Tok::Ident(_))
                && matches!(self.tok_at(1), Tok::Sym(Sym::Assign | Sym::Arrow));
            if named {
                let name = self.ident()?;
                let output = self.at_sym(Sym::Arrow);
                self.bump();
                let value = if output {
                    self.postfix()?
                } else {
                    self.expr()?
                };
                args.push(Arg {
                    name: Some(name),
                    output,
                    value,
                });
            } else {
                args.push(Arg {
                    name: None,
                    output: false,
                    value: self.expr()?,
                });
            }
            if self.eat_sym(Sym::Comma).is_none() {
                return Some(args);
            }
        }
    }

    fn primary(&mut self) -> Option<Expr> {
        let start = self.span();
        let lit = |kind, span| Some(Expr { kind, span });
        match self.tok().clone() {
            Tok::Int(n) => {
                self.bump();
                lit(ExprKind::Lit(Lit::Int(n, None)), start)
            }
            Tok::Real(r) => {
                self.bump();
                lit(ExprKind::Lit(Lit::Real(r, None)), start)
            }
            Tok::Time(ns) => {
                self.bump();
                lit(ExprKind::Lit(Lit::Time(ns)), start)
            }
            Tok::Str(s) => {
                self.bump();
                lit(ExprKind::Lit(Lit::Str(s)), start)
            }
            Tok::Kw(Kw::True) => {
                self.bump();
                lit(ExprKind::Lit(Lit::Bool(true)), start)
            }
            Tok::Kw(Kw::False) => {
                self.bump();
                lit(ExprKind::Lit(Lit::Bool(false)), start)
            }
            Tok::Direct(d) => {
                self.bump();
                lit(ExprKind::Direct(d), start)
            }
            Tok::Sym(Sym::LParen) => {
                self.bump();
                let inner = self.expr()?;
                let end = self.expect_sym(Sym::RParen)?;
                lit(ExprKind::Paren(Box::new(inner)), start.to(end))
            }
            Tok::Ident(_) if *self.tok_at(1) == Tok::Sym(Sym::Hash) => self.typed_literal(),
            Tok::Ident(_) => {
                let i = self.ident()?;
                let span = i.span;
                lit(ExprKind::Name(i), span)
            }
            Tok::Bad => {
                // Reported by the lexer already.
                self.bump();
                None
            }
            _ => {
                self.expected("a value, a variable or `(`");
                None
            }
        }
    }

    /// `TYPE#value`: `INT#5`, `REAL#1.5`, `BOOL#1`, `INT#-3`, or an enumeration's `Dir#Up`.
    fn typed_literal(&mut self) -> Option<Expr> {
        let ty = self.ident()?;
        self.bump();
        let start = ty.span;
        let negative = self.eat_sym(Sym::Minus).is_some();
        let key = ty.key();
        let kind = match self.tok().clone() {
            Tok::Int(n) if key == "BOOL" => match n {
                0 | 1 => ExprKind::Lit(Lit::Bool(n == 1)),
                _ => {
                    let s = self.span();
                    self.error(s, "a BOOL is 0 or 1 (or FALSE, TRUE)");
                    return None;
                }
            },
            Tok::Int(n) => ExprKind::Lit(Lit::Int(n, Some(ty))),
            Tok::Real(r) => ExprKind::Lit(Lit::Real(r, Some(ty))),
            Tok::Kw(Kw::True) if key == "BOOL" => ExprKind::Lit(Lit::Bool(true)),
            Tok::Kw(Kw::False) if key == "BOOL" => ExprKind::Lit(Lit::Bool(false)),
            Tok::Ident(v) if !negative => {
                let span = self.span();
                ExprKind::Lit(Lit::Enum(ty, Ident { text: v, span }))
            }
            _ => {
                self.expected(&format!("a value after `{}#`", ty.text));
                return None;
            }
        };
        let end = self.bump();
        let e = Expr {
            kind,
            span: start.to(end),
        };
        if negative {
            let span = e.span;
            return Some(Expr {
                kind: ExprKind::Unary(UnOp::Neg, Box::new(e)),
                span,
            });
        }
        Some(e)
    }
}
