"""The OMS command language: a streaming lexer, operand values and the operand range tables
(pure)."""
