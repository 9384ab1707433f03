"""The book's equations, one module per worked example: `Book` as printed, `Reference` as derived."""
