"""Report writers: workbook, JSON and text summary, figures."""
