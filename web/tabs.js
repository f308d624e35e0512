// The page's views (web/index.html): a tab button each (button[data-tab]), one view shown at a time
// (section#view-<name>). The address's fragment names the view (#trace), so that a reload or a link keeps it.

export class Tabs {
  #buttons;
  #onChange;
  current = null;

  /** nav: the element holding the buttons; onChange(name, previous) after each switch (not for the first view). */
  constructor(nav, onChange = () => {}) {
    this.#buttons = new Map([...nav.querySelectorAll("button[data-tab]")].map((b) => [b.dataset.tab, b]));
    this.#onChange = onChange;
    for (const [name, button] of this.#buttons) {
      button.addEventListener("click", () => this.show(name));
    }
    const wanted = location.hash.slice(1);
    this.#switch(this.#usable(wanted) ? wanted : "network");
    window.addEventListener("hashchange", () => {
      const name = location.hash.slice(1);
      if (this.#usable(name) && name !== this.current) {
        this.show(name);
      }
    });
  }

  /** Shows the view `name` (a button's data-tab); a disabled one is not shown. */
  show(name) {
    if (!this.#usable(name) || name === this.current) {
      return;
    }
    const previous = this.current;
    this.#switch(name);
    history.replaceState(null, "", `#${name}`);
    this.#onChange(name, previous);
  }

  /** Enables or disables the tab `name` (the node view until a node is picked). */
  enable(name, enabled) {
    this.#buttons.get(name).disabled = !enabled;
  }

  /** The tab button of `name`, for a panel that labels it (the node view: "Node 16"). */
  button(name) {
    return this.#buttons.get(name);
  }

  #usable(name) {
    return this.#buttons.has(name) && !this.#buttons.get(name).disabled;
  }

  #switch(name) {
    this.current = name;
    for (const [tab, button] of this.#buttons) {
      const selected = tab === name;
      button.setAttribute("aria-selected", String(selected));
      document.getElementById(`view-${tab}`).hidden = !selected;
    }
  }
}
