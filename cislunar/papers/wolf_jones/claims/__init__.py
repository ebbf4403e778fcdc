"""Claims of Wolf & Jones, one module per notebook (chapter): declarations only, judged in the notebooks."""
