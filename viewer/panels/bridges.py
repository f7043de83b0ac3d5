"""The Bridges dock: every candidate in a sortable table (quality, factors, endpoints, status).

The "kept" and "why" columns: before a repair, kept = the line arrived; once a repair exists,
kept = the repair's conflict resolution kept it, and "why" gives its reason otherwise.

Selecting a row selects the bridge in the model (its line goes on the timeline and the
inspector shows its factors); a selection made elsewhere (a click in the 3D view) selects the
row.
"""

from __future__ import annotations

import numpy as np
from PySide6.QtCore import QAbstractTableModel, QModelIndex, QSortFilterProxyModel, Qt
from PySide6.QtGui import QColor
from PySide6.QtWidgets import QAbstractItemView, QHeaderView, QTableView, QVBoxLayout, QWidget

from ..scene import STATUS_COLOURS, bridge_verdicts

_ROOT = QModelIndex()
COLUMNS = ("#", "status", "kept", "quality", "Q", "q_T", "q12", "q3", "q4", "start", "end", "steps", "length", "why")


def _text(column: int, v) -> str:
    if isinstance(v, float):
        return "" if np.isnan(v) else f"{v:.4g}"
    if column == 10 and v < 0:
        return "-"
    return str(v)


class BridgeTableModel(QAbstractTableModel):
    def __init__(self, parent=None) -> None:
        super().__init__(parent)
        self.rows: list[tuple] = []
        self.text: list[tuple[str, ...]] = []  # what the cells show (formatted once per result)
        self.status: list[str] = []

    def set_result(self, result, repair=None) -> None:
        """Rows of a BridgeSet; kept / why from the repair when one is given (else: arrived)."""
        self.beginResetModel()
        self.rows, self.status = [], []
        if result is not None:
            kept, why = bridge_verdicts(result, repair)
            for i, c in enumerate(result.candidates):
                f = c.factors
                fac = (f.Q, f.qT, f.q12, f.q3, f.q4) if f is not None else (np.nan,) * 5
                line = c.line
                self.rows.append((i, line.status, "yes" if kept[i] else "no", float(c.quality), *map(float, fac),
                                  int(line.start_vertex), int(line.end_vertex), int(line.steps), float(line.length),
                                  why[i]))
                self.status.append(line.status)
        self.text = [tuple(_text(c, v) for c, v in enumerate(row)) for row in self.rows]
        self.endResetModel()

    def rowCount(self, parent=_ROOT) -> int:  # noqa: N802
        return 0 if parent.isValid() else len(self.rows)

    def columnCount(self, parent=_ROOT) -> int:  # noqa: N802
        return len(COLUMNS)

    def headerData(self, section, orientation, role=Qt.DisplayRole):  # noqa: N802
        if role == Qt.DisplayRole and orientation == Qt.Horizontal:
            return COLUMNS[section]
        return None

    def data(self, index, role=Qt.DisplayRole):
        if not index.isValid():
            return None
        if role == Qt.DisplayRole:
            return self.text[index.row()][index.column()]
        v = self.rows[index.row()][index.column()]
        if role == Qt.UserRole:  # sort key
            return v
        if role == Qt.ForegroundRole and index.column() == 1:
            return QColor(STATUS_COLOURS.get(v, "#000000"))
        if role == Qt.TextAlignmentRole and not isinstance(v, str):
            return int(Qt.AlignRight | Qt.AlignVCenter)
        return None


class BridgesPanel(QWidget):
    def __init__(self, model, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.model = model
        self.table_model = BridgeTableModel(self)
        self.proxy = QSortFilterProxyModel(self)
        self.proxy.setSourceModel(self.table_model)
        self.proxy.setSortRole(Qt.UserRole)
        self.view = QTableView()
        self.view.setModel(self.proxy)
        self.view.setSortingEnabled(True)
        self.view.sortByColumn(3, Qt.DescendingOrder)
        self.view.setSelectionBehavior(QAbstractItemView.SelectRows)
        self.view.setSelectionMode(QAbstractItemView.SingleSelection)
        self.view.verticalHeader().setVisible(False)
        self.view.horizontalHeader().setSectionResizeMode(QHeaderView.Interactive)
        self._sized_for = -1  # columns are fitted to their contents when the row count changes
        lay = QVBoxLayout(self)
        lay.setContentsMargins(2, 2, 2, 2)
        lay.addWidget(self.view)
        self._syncing = False
        model.resultChanged.connect(self._refresh)
        model.repairChanged.connect(self._refresh)
        model.selectionChanged.connect(self.show_selection)
        self.view.selectionModel().selectionChanged.connect(self._row_selected)

    def _refresh(self, *_) -> None:
        self.table_model.set_result(self.model.result, self.model.repair)
        n = self.table_model.rowCount()
        if n != self._sized_for:
            self._sized_for = n
            self.view.resizeColumnsToContents()
        self.show_selection(self.model.selection)

    def source_row(self, view_row: int) -> int:
        return self.proxy.mapToSource(self.proxy.index(view_row, 0)).row()

    def view_row(self, source_row: int) -> int:
        return self.proxy.mapFromSource(self.table_model.index(source_row, 0)).row()

    def _row_selected(self, *_):
        if self._syncing:
            return
        rows = self.view.selectionModel().selectedRows()
        if rows:
            self.model.select(self.proxy.mapToSource(rows[0]).row())

    def show_selection(self, index: int) -> None:
        self._syncing = True
        try:
            if index < 0:
                self.view.clearSelection()
            else:
                r = self.view_row(index)
                self.view.selectRow(r)
                self.view.scrollTo(self.proxy.index(r, 0))
        finally:
            self._syncing = False
