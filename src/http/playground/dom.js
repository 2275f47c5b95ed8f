// Building elements: the one helper the other modules share.

let serial = 0;

/** A fresh element id with a readable stem. */
export function uid(stem) {
  serial += 1;
  return `${stem}-${serial}`;
}

/**
 * An element: `attributes` are set as attributes (`class`, `text` for the
 * text content; `true` sets a boolean attribute, `false` and `undefined`
 * leave it out), `children` appended.
 */
export function el(tag, attributes = {}, ...children) {
  const node = document.createElement(tag);
  for (const [name, value] of Object.entries(attributes)) {
    if (value === undefined || value === null || value === false) continue;
    if (name === 'text') node.textContent = value;
    else if (name === 'class') node.className = value;
    else node.setAttribute(name, value === true ? '' : String(value));
  }
  node.append(...children.filter((child) => child !== null && child !== undefined && child !== false));
  return node;
}

/** A number as the page shows it: four places, no negative zero. */
export function fixed(value, places = 4) {
  if (typeof value !== 'number' || !Number.isFinite(value)) return String(value);
  const text = value.toFixed(places);
  return /^-0\.?0*$/.test(text) ? text.slice(1) : text;
}
