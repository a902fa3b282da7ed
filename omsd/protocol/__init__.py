"""The OMS command language: a streaming lexer and operand values (pure)."""
