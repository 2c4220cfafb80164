// Which of the board's listings (`geometry`, `config`) a command line can change, so the view
// asks for them again: the rule is the data file listing-changes.txt beside this one, which the
// host tool's view server (cli/src/view/follow.rs) builds in too, so the two servers cannot
// disagree.

import { readFileSync } from 'node:fs';

/** The rule file's text. */
export const RULE_TEXT = readFileSync(new URL('./listing-changes.txt', import.meta.url), 'utf8');

/** A line's words as the board reads them: lower case, split at spaces, tabs and commas. */
function words(line) {
  return line
    .trim()
    .toLowerCase()
    .split(/[\s,]+/)
    .filter((word) => word !== '');
}

/**
 * The rules: `{ pattern: [word, ...], listings: [name, ...] }` in file order (a pattern word
 * ending in `*` matches any word that starts so).
 */
export const RULES = RULE_TEXT.split('\n')
  .filter((line) => line.trim() !== '' && !line.startsWith('#'))
  .map((line) => {
    const [pattern, listings, ...rest] = line.split('->');
    if (listings === undefined || rest.length > 0) {
      throw new Error(`listing-changes.txt: not 'words -> listings': ${line}`);
    }
    return { pattern: words(pattern), listings: words(listings) };
  });

/** Whether a pattern word matches a line's word. */
function matches(pattern, word) {
  return pattern.endsWith('*') ? word.startsWith(pattern.slice(0, -1)) : word === pattern;
}

/**
 * Which listings a command line can change: `[]`, or some of `'geometry'` and `'config'`, by
 * the first rule whose words begin the line.
 * @param {string} line
 * @returns {string[]}
 */
export function listingsChangedBy(line) {
  const said = words(line);
  const rule = RULES.find(
    ({ pattern }) =>
      pattern.length <= said.length && pattern.every((word, i) => matches(word, said[i])),
  );
  return rule ? [...rule.listings] : [];
}
