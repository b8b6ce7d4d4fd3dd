//! Curriculum expressions: arithmetic on `f64` over named values, e.g.
//! `min(0.08 + 0.025 * level, 0.20)`.
//!
//! Grammar: numbers, names (`level`, `max_level`, `pi` and the task's
//! parameters), `+ - * /`, unary minus, parentheses, and the functions
//! `min(a, b, ...)`, `max(a, b, ...)`, `abs(x)`, `sqrt(x)`, `sin(x)`, `cos(x)`.
//! Every value is a float (there is no integer division to trip over), and
//! `min`/`max` fold left with `f64::min`/`f64::max`, so the built-in
//! curricula evaluate to exactly the values of the original code.
//!
//! Written here rather than taken from an expression crate: the ones on
//! crates.io either mix integer and float arithmetic (`level / 2` would be an
//! integer division) or are unmaintained, and ours reports the column of an error.

use std::fmt;

/// An expression parsed from text.
#[derive(Debug, Clone, PartialEq)]
pub enum Expr {
    /// A literal.
    Num(f64),
    /// A named value.
    Var(String),
    /// `-x`.
    Neg(Box<Expr>),
    /// `a op b`.
    Bin(Op, Box<Expr>, Box<Expr>),
    /// `f(args)`.
    Call(Func, Vec<Expr>),
}

/// A binary operator.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Op {
    Add,
    Sub,
    Mul,
    Div,
}

/// A function.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Func {
    Min,
    Max,
    Abs,
    Sqrt,
    Sin,
    Cos,
}

impl Func {
    fn named(name: &str) -> Option<Func> {
        Some(match name {
            "min" => Func::Min,
            "max" => Func::Max,
            "abs" => Func::Abs,
            "sqrt" => Func::Sqrt,
            "sin" => Func::Sin,
            "cos" => Func::Cos,
            _ => return None,
        })
    }
}

/// A syntax error, with the 1-based column where it was found.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ParseError {
    /// Column (characters, 1-based).
    pub column: usize,
    /// What is wrong.
    pub message: String,
}

impl fmt::Display for ParseError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "column {}: {}", self.column, self.message)
    }
}

#[derive(Debug, Clone, PartialEq)]
enum Tok {
    Num(f64),
    Name(String),
    Sym(char),
}

fn tokens(text: &str) -> Result<Vec<(usize, Tok)>, ParseError> {
    let chars: Vec<char> = text.chars().collect();
    let mut out = Vec::new();
    let mut i = 0;
    while i < chars.len() {
        let c = chars[i];
        if c.is_whitespace() {
            i += 1;
        } else if c.is_ascii_digit() || c == '.' {
            let start = i;
            while i < chars.len()
                && (chars[i].is_ascii_digit()
                    || chars[i] == '.'
                    || chars[i] == 'e'
                    || chars[i] == 'E'
                    || ((chars[i] == '-' || chars[i] == '+') && matches!(chars[i - 1], 'e' | 'E')))
            {
                i += 1;
            }
            let s: String = chars[start..i].iter().collect();
            let v = s
                .parse::<f64>()
                .map_err(|_| ParseError { column: start + 1, message: format!("{s:?} is not a number") })?;
            out.push((start + 1, Tok::Num(v)));
        } else if c.is_alphabetic() || c == '_' {
            let start = i;
            while i < chars.len() && (chars[i].is_alphanumeric() || chars[i] == '_') {
                i += 1;
            }
            out.push((start + 1, Tok::Name(chars[start..i].iter().collect())));
        } else if "+-*/(),".contains(c) {
            out.push((i + 1, Tok::Sym(c)));
            i += 1;
        } else {
            return Err(ParseError { column: i + 1, message: format!("unexpected character {c:?}") });
        }
    }
    Ok(out)
}

struct Parser {
    toks: Vec<(usize, Tok)>,
    pos: usize,
    end: usize,
}

impl Parser {
    fn peek(&self) -> Option<&Tok> {
        self.toks.get(self.pos).map(|t| &t.1)
    }
    fn column(&self) -> usize {
        self.toks.get(self.pos).map_or(self.end, |t| t.0)
    }
    fn err<T>(&self, message: impl Into<String>) -> Result<T, ParseError> {
        Err(ParseError { column: self.column(), message: message.into() })
    }
    fn eat(&mut self, c: char) -> bool {
        if self.peek() == Some(&Tok::Sym(c)) {
            self.pos += 1;
            true
        } else {
            false
        }
    }
    fn sum(&mut self) -> Result<Expr, ParseError> {
        let mut left = self.product()?;
        loop {
            let op = if self.eat('+') {
                Op::Add
            } else if self.eat('-') {
                Op::Sub
            } else {
                return Ok(left);
            };
            left = Expr::Bin(op, Box::new(left), Box::new(self.product()?));
        }
    }
    fn product(&mut self) -> Result<Expr, ParseError> {
        let mut left = self.unary()?;
        loop {
            let op = if self.eat('*') {
                Op::Mul
            } else if self.eat('/') {
                Op::Div
            } else {
                return Ok(left);
            };
            left = Expr::Bin(op, Box::new(left), Box::new(self.unary()?));
        }
    }
    fn unary(&mut self) -> Result<Expr, ParseError> {
        if self.eat('-') {
            return Ok(Expr::Neg(Box::new(self.unary()?)));
        }
        if self.eat('+') {
            return self.unary();
        }
        self.atom()
    }
    fn atom(&mut self) -> Result<Expr, ParseError> {
        match self.peek().cloned() {
            Some(Tok::Num(v)) => {
                self.pos += 1;
                Ok(Expr::Num(v))
            }
            Some(Tok::Name(name)) => {
                let column = self.column();
                self.pos += 1;
                if !self.eat('(') {
                    return Ok(Expr::Var(name));
                }
                let Some(func) = Func::named(&name) else {
                    return Err(ParseError {
                        column,
                        message: format!("unknown function {name:?} (known: min, max, abs, sqrt, sin, cos)"),
                    });
                };
                let mut args = vec![self.sum()?];
                while self.eat(',') {
                    args.push(self.sum()?);
                }
                if !self.eat(')') {
                    return self.err("expected ',' or ')'");
                }
                let arity_ok = match func {
                    Func::Min | Func::Max => !args.is_empty(),
                    _ => args.len() == 1,
                };
                if !arity_ok {
                    return Err(ParseError { column, message: format!("{name} takes one argument") });
                }
                Ok(Expr::Call(func, args))
            }
            Some(Tok::Sym('(')) => {
                self.pos += 1;
                let e = self.sum()?;
                if !self.eat(')') {
                    return self.err("expected ')'");
                }
                Ok(e)
            }
            Some(t) => self.err(format!("unexpected {}", describe(&t))),
            None => self.err("unexpected end of expression"),
        }
    }
}

fn describe(t: &Tok) -> String {
    match t {
        Tok::Num(v) => format!("number {v}"),
        Tok::Name(n) => format!("name {n:?}"),
        Tok::Sym(c) => format!("{c:?}"),
    }
}

impl Expr {
    /// Parses `text`.
    ///
    /// # Errors
    /// [`ParseError`] with the column of the first problem.
    pub fn parse(text: &str) -> Result<Expr, ParseError> {
        let toks = tokens(text)?;
        let mut p = Parser { toks, pos: 0, end: text.chars().count() + 1 };
        let e = p.sum()?;
        if p.pos < p.toks.len() {
            let t = p.toks[p.pos].1.clone();
            return p.err(format!("unexpected {} after a complete expression", describe(&t)));
        }
        Ok(e)
    }

    /// Every name the expression reads.
    pub fn names(&self) -> Vec<&str> {
        let mut out = Vec::new();
        self.collect_names(&mut out);
        out
    }

    fn collect_names<'a>(&'a self, out: &mut Vec<&'a str>) {
        match self {
            Expr::Num(_) => {}
            Expr::Var(n) => out.push(n),
            Expr::Neg(e) => e.collect_names(out),
            Expr::Bin(_, a, b) => {
                a.collect_names(out);
                b.collect_names(out);
            }
            Expr::Call(_, args) => args.iter().for_each(|a| a.collect_names(out)),
        }
    }

    /// Evaluates with `lookup` giving each name's value (`None`: unknown name).
    ///
    /// # Errors
    /// The first unknown name.
    pub(crate) fn eval(&self, lookup: &dyn Fn(&str) -> Option<f64>) -> Result<f64, String> {
        Ok(match self {
            Expr::Num(v) => *v,
            Expr::Var(n) => lookup(n).ok_or_else(|| format!("unknown name {n:?}"))?,
            Expr::Neg(e) => -e.eval(lookup)?,
            Expr::Bin(op, a, b) => {
                let (a, b) = (a.eval(lookup)?, b.eval(lookup)?);
                match op {
                    Op::Add => a + b,
                    Op::Sub => a - b,
                    Op::Mul => a * b,
                    Op::Div => a / b,
                }
            }
            Expr::Call(f, args) => {
                let vals: Vec<f64> = args.iter().map(|a| a.eval(lookup)).collect::<Result<_, _>>()?;
                match f {
                    Func::Min => vals[1..].iter().fold(vals[0], |m, &v| m.min(v)),
                    Func::Max => vals[1..].iter().fold(vals[0], |m, &v| m.max(v)),
                    Func::Abs => vals[0].abs(),
                    Func::Sqrt => vals[0].sqrt(),
                    Func::Sin => vals[0].sin(),
                    Func::Cos => vals[0].cos(),
                }
            }
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn eval(text: &str, level: f64) -> f64 {
        Expr::parse(text).unwrap().eval(&|n| (n == "level").then_some(level)).unwrap()
    }

    #[test]
    fn builtin_curricula_match_the_original_arithmetic() {
        for level in 0..=12 {
            let l = level as f64;
            assert_eq!(eval("min(0.08 + 0.025 * level, 0.20)", l), (0.08 + 0.025 * l).min(0.20));
            assert_eq!(eval("max(0.20 - 0.02 * level, 0)", l), (0.20 - 0.02 * l).max(0.0));
        }
    }

    #[test]
    fn precedence_unary_minus_and_float_division() {
        assert_eq!(eval("1 + 2 * 3", 0.0), 7.0);
        assert_eq!(eval("(1 + 2) * 3", 0.0), 9.0);
        assert_eq!(eval("-level / 2", 3.0), -1.5);
        assert_eq!(eval("2 - -1", 0.0), 3.0);
        assert_eq!(eval("1e-2 * 100", 0.0), 1.0);
        assert_eq!(eval("max(1, 5, 3)", 0.0), 5.0);
    }

    #[test]
    fn errors_name_the_column() {
        let e = Expr::parse("0.08 + * level").unwrap_err();
        assert_eq!(e.column, 8, "{e}");
        let e = Expr::parse("min(1, 2").unwrap_err();
        assert!(e.message.contains("')'"), "{e}");
        let e = Expr::parse("floor(2)").unwrap_err();
        assert!(e.message.contains("unknown function \"floor\""), "{e}");
        let e = Expr::parse("1 2").unwrap_err();
        assert_eq!(e.column, 3, "{e}");
        assert!(Expr::parse("").is_err());
        assert!(Expr::parse("2 $ 3").unwrap_err().message.contains("'$'"));
        assert_eq!(Expr::parse("R + level").unwrap().names(), vec!["R", "level"]);
    }
}
