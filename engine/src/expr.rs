//! Count expressions of resources, start passes and operators, e.g. `WIDTH * HEIGHT` or
//! `LIGHT_PATHS * AVG_LIGHT_LENGTH * 1.1`, and the constant conditions of `enabled`, e.g.
//! `MERGE && MAX_PATH_LENGTH > 2`.
//!
//! Expressions are evaluated in `f64` over named constants (a `bool` is 0 or 1; comparisons
//! and `!`, `&&`, `||` give 0 or 1); counts are rounded up to a whole number.

use std::collections::BTreeMap;

/// The most tokens an expression may have (which bounds how deep it nests).
const MAX_TOKENS: usize = 256;

/// A binary operator.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BinOp {
    /// `+`
    Add,
    /// `-`
    Sub,
    /// `*`
    Mul,
    /// `/`
    Div,
    /// `<`
    Lt,
    /// `<=`
    Le,
    /// `>`
    Gt,
    /// `>=`
    Ge,
    /// `==`
    Eq,
    /// `!=`
    Ne,
    /// `&&`
    And,
    /// `||`
    Or,
}

impl BinOp {
    fn apply(self, a: f64, b: f64) -> f64 {
        let truth = |c: bool| c as u8 as f64;
        match self {
            BinOp::Add => a + b,
            BinOp::Sub => a - b,
            BinOp::Mul => a * b,
            BinOp::Div => a / b,
            BinOp::Lt => truth(a < b),
            BinOp::Le => truth(a <= b),
            BinOp::Gt => truth(a > b),
            BinOp::Ge => truth(a >= b),
            BinOp::Eq => truth(a == b),
            BinOp::Ne => truth(a != b),
            BinOp::And => truth(a != 0.0 && b != 0.0),
            BinOp::Or => truth(a != 0.0 || b != 0.0),
        }
    }
}

/// A parsed expression.
#[derive(Debug, Clone, PartialEq)]
pub enum Expr {
    /// A number literal.
    Number(f64),
    /// A named constant.
    Name(String),
    /// `-x`
    Neg(Box<Expr>),
    /// `!x`: 1 when x is 0, else 0.
    Not(Box<Expr>),
    /// A binary operation.
    Binary(Box<Expr>, BinOp, Box<Expr>),
    /// A call of `min`, `max`, `ceil`, `floor` or `pow`.
    Call(String, Vec<Expr>),
}

impl Expr {
    /// Parses `text`; the error names what was expected.
    pub fn parse(text: &str) -> Result<Expr, String> {
        let tokens = tokenize(text)?;
        // The parser, evaluation and drop recurse as deep as the expression nests.
        if tokens.len() > MAX_TOKENS {
            return Err(format!(
                "count expression of {} tokens is too long (at most {MAX_TOKENS})",
                tokens.len()
            ));
        }
        let mut parser = Parser { tokens, pos: 0 };
        let expr = parser.or()?;
        if parser.pos != parser.tokens.len() {
            return Err(format!(
                "unexpected '{}' in count expression '{text}'",
                parser.tokens[parser.pos].text()
            ));
        }
        Ok(expr)
    }

    /// The names the expression uses.
    pub fn names(&self) -> Vec<String> {
        let mut out = Vec::new();
        self.collect_names(&mut out);
        out
    }

    fn collect_names(&self, out: &mut Vec<String>) {
        match self {
            Expr::Number(_) => {}
            Expr::Name(n) => out.push(n.clone()),
            Expr::Neg(a) | Expr::Not(a) => a.collect_names(out),
            Expr::Binary(a, _, b) => {
                a.collect_names(out);
                b.collect_names(out);
            }
            Expr::Call(_, args) => args.iter().for_each(|a| a.collect_names(out)),
        }
    }

    /// Evaluates with `vars`; the error names an unknown constant.
    pub fn eval(&self, vars: &BTreeMap<String, f64>) -> Result<f64, String> {
        Ok(match self {
            Expr::Number(v) => *v,
            Expr::Name(n) => *vars.get(n).ok_or_else(|| {
                let known: Vec<&str> = vars.keys().map(|k| k.as_str()).collect();
                format!(
                    "unknown constant '{n}' in count expression (known: {})",
                    known.join(", ")
                )
            })?,
            Expr::Neg(a) => -a.eval(vars)?,
            Expr::Not(a) => (a.eval(vars)? == 0.0) as u8 as f64,
            Expr::Binary(a, op, b) => op.apply(a.eval(vars)?, b.eval(vars)?),
            Expr::Call(f, args) => {
                let v: Vec<f64> = args.iter().map(|a| a.eval(vars)).collect::<Result<_, _>>()?;
                match (f.as_str(), v.as_slice()) {
                    ("min", [a, b]) => a.min(*b),
                    ("max", [a, b]) => a.max(*b),
                    ("ceil", [a]) => a.ceil(),
                    ("floor", [a]) => a.floor(),
                    ("pow", [a, b]) => a.powf(*b),
                    _ => {
                        return Err(format!(
                            "unknown function {f}/{} (min/2, max/2, ceil/1, floor/1, pow/2)",
                            v.len()
                        ));
                    }
                }
            }
        })
    }

    /// Evaluates and rounds up to a count; negative, infinite or NaN results are errors.
    pub fn count(&self, vars: &BTreeMap<String, f64>) -> Result<u64, String> {
        let v = self.eval(vars)?;
        if !v.is_finite() || !(0.0..=1e18).contains(&v) {
            return Err(format!("count expression evaluates to {v}, not a count"));
        }
        Ok(v.ceil() as u64)
    }
}

#[derive(Debug, Clone, PartialEq)]
enum Token {
    Num(f64),
    Ident(String),
    Sym(&'static str),
}

impl Token {
    fn text(&self) -> String {
        match self {
            Token::Num(v) => v.to_string(),
            Token::Ident(s) => s.clone(),
            Token::Sym(c) => c.to_string(),
        }
    }
}

/// Symbols, two-character ones first.
const SYMBOLS: [&str; 16] = [
    "<=", ">=", "==", "!=", "&&", "||", "+", "-", "*", "/", "(", ")", ",", "<", ">", "!",
];

fn tokenize(text: &str) -> Result<Vec<Token>, String> {
    let chars: Vec<char> = text.chars().collect();
    let mut out = Vec::new();
    let mut i = 0;
    while i < chars.len() {
        let c = chars[i];
        if c.is_whitespace() {
            i += 1;
        } else if c.is_ascii_digit() || c == '.' {
            let start = i;
            while i < chars.len() && (chars[i].is_ascii_digit() || chars[i] == '.' || chars[i] == 'e') {
                i += 1;
            }
            let s: String = chars[start..i].iter().collect();
            out.push(Token::Num(
                s.parse()
                    .map_err(|_| format!("bad number '{s}' in count expression '{text}'"))?,
            ));
        } else if c.is_alphabetic() || c == '_' {
            let start = i;
            while i < chars.len() && (chars[i].is_alphanumeric() || chars[i] == '_') {
                i += 1;
            }
            out.push(Token::Ident(chars[start..i].iter().collect()));
        } else {
            let rest: String = chars[i..chars.len().min(i + 2)].iter().collect();
            let sym = SYMBOLS
                .iter()
                .find(|s| rest.starts_with(**s))
                .ok_or_else(|| format!("unexpected character '{c}' in count expression '{text}'"))?;
            out.push(Token::Sym(sym));
            i += sym.len();
        }
    }
    Ok(out)
}

struct Parser {
    tokens: Vec<Token>,
    pos: usize,
}

impl Parser {
    fn peek_sym(&self) -> Option<&'static str> {
        match self.tokens.get(self.pos) {
            Some(Token::Sym(c)) => Some(c),
            _ => None,
        }
    }

    fn expect(&mut self, c: &str) -> Result<(), String> {
        if self.peek_sym() == Some(c) {
            self.pos += 1;
            Ok(())
        } else {
            Err(format!("expected '{c}' in count expression"))
        }
    }

    /// One level of left-associative binary operators, over operands parsed by `next`.
    fn level(&mut self, ops: &[(&str, BinOp)], next: fn(&mut Parser) -> Result<Expr, String>) -> Result<Expr, String> {
        let mut lhs = next(self)?;
        while let Some(&(_, op)) = self.peek_sym().and_then(|s| ops.iter().find(|(t, _)| *t == s)) {
            self.pos += 1;
            lhs = Expr::Binary(Box::new(lhs), op, Box::new(next(self)?));
        }
        Ok(lhs)
    }

    fn or(&mut self) -> Result<Expr, String> {
        self.level(&[("||", BinOp::Or)], Parser::and)
    }

    fn and(&mut self) -> Result<Expr, String> {
        self.level(&[("&&", BinOp::And)], Parser::comparison)
    }

    fn comparison(&mut self) -> Result<Expr, String> {
        self.level(
            &[
                ("<", BinOp::Lt),
                ("<=", BinOp::Le),
                (">", BinOp::Gt),
                (">=", BinOp::Ge),
                ("==", BinOp::Eq),
                ("!=", BinOp::Ne),
            ],
            Parser::sum,
        )
    }

    fn sum(&mut self) -> Result<Expr, String> {
        self.level(&[("+", BinOp::Add), ("-", BinOp::Sub)], Parser::product)
    }

    fn product(&mut self) -> Result<Expr, String> {
        self.level(&[("*", BinOp::Mul), ("/", BinOp::Div)], Parser::unary)
    }

    fn unary(&mut self) -> Result<Expr, String> {
        match self.peek_sym() {
            Some("-") => {
                self.pos += 1;
                Ok(Expr::Neg(Box::new(self.unary()?)))
            }
            Some("!") => {
                self.pos += 1;
                Ok(Expr::Not(Box::new(self.unary()?)))
            }
            _ => self.atom(),
        }
    }

    fn atom(&mut self) -> Result<Expr, String> {
        let token = self
            .tokens
            .get(self.pos)
            .cloned()
            .ok_or("count expression ends too early")?;
        self.pos += 1;
        match token {
            Token::Num(v) => Ok(Expr::Number(v)),
            Token::Ident(name) if self.peek_sym() == Some("(") => {
                self.pos += 1;
                let mut args = vec![self.or()?];
                while self.peek_sym() == Some(",") {
                    self.pos += 1;
                    args.push(self.or()?);
                }
                self.expect(")")?;
                Ok(Expr::Call(name, args))
            }
            Token::Ident(name) => Ok(Expr::Name(name)),
            Token::Sym("(") => {
                let e = self.or()?;
                self.expect(")")?;
                Ok(e)
            }
            Token::Sym(c) => Err(format!("unexpected '{c}' in count expression")),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn vars() -> BTreeMap<String, f64> {
        [("WIDTH".to_string(), 640.0), ("HEIGHT".to_string(), 480.0)]
            .into_iter()
            .collect()
    }

    #[test]
    fn evaluates_with_precedence_and_rounds_up() {
        let e = Expr::parse("WIDTH * HEIGHT + 2 * 3").unwrap();
        assert_eq!(e.count(&vars()).unwrap(), 640 * 480 + 6);
        assert_eq!(Expr::parse("(WIDTH + 1) / 2").unwrap().count(&vars()).unwrap(), 321);
        assert_eq!(
            Expr::parse("max(WIDTH, HEIGHT) * 1.25 + 0.5")
                .unwrap()
                .count(&vars())
                .unwrap(),
            801
        );
        assert_eq!(Expr::parse("WIDTH*HEIGHT").unwrap().names(), vec!["WIDTH", "HEIGHT"]);
        assert_eq!(Expr::parse("-2 * -WIDTH").unwrap().eval(&vars()).unwrap(), 1280.0);
        assert_eq!(Expr::parse("pow(2, 10)").unwrap().eval(&vars()).unwrap(), 1024.0);
    }

    #[test]
    fn evaluates_conditions() {
        let cases = [
            ("WIDTH > HEIGHT", 1.0),
            ("WIDTH <= HEIGHT", 0.0),
            ("!(WIDTH == 640) || HEIGHT != 480", 0.0),
            ("WIDTH >= 640 && HEIGHT < 481", 1.0),
            ("!0 + 1 > 1", 1.0),
            ("1 + 1 == 2 && 0 || 1", 1.0),
        ];
        for (text, want) in cases {
            assert_eq!(Expr::parse(text).unwrap().eval(&vars()).unwrap(), want, "{text}");
        }
        assert!(Expr::parse("WIDTH >").is_err());
        assert!(Expr::parse("WIDTH & HEIGHT").is_err());
    }

    #[test]
    fn reports_errors() {
        assert!(Expr::parse("WIDTH *").is_err());
        assert!(Expr::parse("WIDTH $ 2").is_err());
        assert!(Expr::parse("(WIDTH").is_err());
        let err = Expr::parse("DEPTH").unwrap().count(&vars()).unwrap_err();
        assert!(err.contains("DEPTH"), "{err}");
        assert!(Expr::parse("0 - WIDTH").unwrap().count(&vars()).is_err());
    }

    #[test]
    fn deep_nesting_is_an_error_not_a_stack_overflow() {
        let deep = format!("{}WIDTH{}", "(".repeat(5000), ")".repeat(5000));
        assert!(Expr::parse(&deep).unwrap_err().contains("10001 tokens is too long"));
        assert!(Expr::parse(&vec!["WIDTH"; 5000].join(" + ")).is_err());
        let nested = format!("{}WIDTH{}", "(".repeat(100), ")".repeat(100));
        assert_eq!(Expr::parse(&nested).unwrap().count(&vars()).unwrap(), 640);
    }
}
