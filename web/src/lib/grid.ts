/** Columns and cell size that fit n square clips into a box without scrolling. */
export function bestGrid(
  n: number,
  width: number,
  height: number,
  gap = 8,
): { cols: number; cell: number } {
  let best = { cols: 1, cell: 0 };
  for (let cols = 1; cols <= Math.max(1, n); cols++) {
    const rows = Math.ceil(n / cols);
    const cell = Math.floor(
      Math.min((width - gap * (cols - 1)) / cols, (height - gap * (rows - 1)) / rows),
    );
    if (cell > best.cell) best = { cols, cell };
  }
  return best;
}
