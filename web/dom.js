// Small DOM helpers the views share. Text goes in as textContent (never markup: nothing the emulator says becomes
// HTML), properties by assignment (no inline style attribute: the Content-Security-Policy allows none).

/** A new element with `properties` assigned (className, textContent, type...) and `children` appended. */
export function element(tag, properties = {}, ...children) {
  const e = Object.assign(document.createElement(tag), properties);
  e.append(...children);
  return e;
}

/** The head row of `table` from columns [{field, title}]: a th per column, its field as data-field. */
export function tableHead(table, columns) {
  const head = table.createTHead().insertRow();
  for (const {field, title} of columns) {
    const th = element("th", {textContent: title, scope: "col"});
    th.dataset.field = field;
    head.append(th);
  }
  return head;
}
