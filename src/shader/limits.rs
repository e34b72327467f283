//! Limits that keep naga's recursive descent off the end of the stack. naga bounds
//! brace and parenthesis nesting itself but not operator chains: `1 + 1 + … + 1` nests
//! one expression per operator, and 5,000 overflow a 2 MiB thread. The text is checked
//! before naga sees it, and naga runs on a thread with room to spare.

/// Most `#include` levels (a chain of files including each other, or generated code).
pub const MAX_INCLUDE_DEPTH: usize = 32;
/// Most operators in one statement (between `;`, `{` and `}`).
pub const MAX_OPERATORS_PER_STATEMENT: usize = 1024;
/// Stack of the thread naga parses and validates on: 8× what the operator limit needs.
pub const NAGA_STACK_BYTES: usize = 32 << 20;

/// The 1-based line where the first statement with more operators than the limit starts.
pub fn longest_statement_over_limit(text: &str) -> Option<usize> {
    let (mut count, mut start_line, mut line) = (0usize, 1usize, 1usize);
    let mut chars = text.chars().peekable();
    while let Some(c) = chars.next() {
        match c {
            '\n' => line += 1,
            '/' if chars.peek() == Some(&'/') => {
                for c in chars.by_ref() {
                    if c == '\n' {
                        line += 1;
                        break;
                    }
                }
            }
            ';' | '{' | '}' => {
                count = 0;
                start_line = line;
            }
            '+' | '-' | '*' | '/' | '%' | '&' | '|' | '^' | '!' | '~' | '<' | '>' | '[' | '(' => {
                if count == 0 {
                    start_line = line;
                }
                count += 1;
                if count > MAX_OPERATORS_PER_STATEMENT {
                    return Some(start_line);
                }
            }
            _ => {}
        }
    }
    None
}

/// Runs `f` (naga) on a thread with [`NAGA_STACK_BYTES`] of stack.
pub fn on_naga_stack<T: Send>(f: impl FnOnce() -> T + Send) -> T {
    std::thread::scope(|s| {
        std::thread::Builder::new()
            .name("naga".into())
            .stack_size(NAGA_STACK_BYTES)
            .spawn_scoped(s, f)
            .expect("spawning the naga thread")
            .join()
            .unwrap_or_else(|p| std::panic::resume_unwind(p))
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_operators_per_statement() {
        let ok = format!(
            "const a = 1{};\nconst b = 1{};",
            " + 1".repeat(1000),
            " + 1".repeat(1000)
        );
        assert_eq!(longest_statement_over_limit(&ok), None);
        let long = format!("fn f() {{\n}}\nconst x = 1{};", " + 1".repeat(20_000));
        assert_eq!(longest_statement_over_limit(&long), Some(3));
        // Comments count nothing.
        let commented = format!("// {}\nconst a = 1;", "+".repeat(5000));
        assert_eq!(longest_statement_over_limit(&commented), None);
    }
}
