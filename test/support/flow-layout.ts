/**
 * How a flow looks in the Node-RED editor and on a Dashboard 2.0 page,
 * judged from its JSON: the boxes the editor draws (estimated, never smaller
 * than drawn: test/browser.test.ts checks the estimate against the editor's
 * own sizes) and the widths of dashboard groups and widgets.
 */

export interface FlowNode {
  id: string;
  type: string;
  z?: string;
  x?: number;
  y?: number;
  name?: string;
  label?: string;
  l?: boolean;
  outputs?: number;
  wires?: unknown[];
  [key: string]: unknown;
}

export interface Box {
  id: string;
  label: string;
  left: number;
  top: number;
  right: number;
  bottom: number;
}

/**
 * The editor's node size (editor-client view.js): 30 px high or 15 px per
 * output, and `max(100, 20 * ceil((label + 50 + 7 if it has an input) / 20))`
 * wide. The label is taken at 8 px a character (the editor's 14 px sans-serif
 * averages about 7), and no node is taken narrower than 140 px.
 */
export const LABEL_PX_PER_CHAR = 8;
export const MIN_NODE_WIDTH = 140;
export const NODE_HEIGHT = 30;

/** How far a node's status (dot and text) reaches below its box: drawn 3 px under it, 14 px high. */
export const STATUS_BELOW = 20;
/** Types that show a status under the node while the flow runs. */
const SHOWS_STATUS = new Set([
  'plcwire-read',
  'plcwire-write',
  'plcwire-heartbeat',
  'plcwire-control',
  'plcwire-alarms',
  'ui-switch',
  'ui-slider',
  'trigger',
]);

/**
 * Node buttons the editor draws beside a node's body (editor-client view.js: a
 * 32 px button at x -25, or at width - 6 for a right-aligned one): how far each
 * reaches past the body's left or right edge.
 */
export const BUTTON_LEFT: Readonly<Record<string, number>> = Object.freeze({ inject: 25 });
export const BUTTON_RIGHT: Readonly<Record<string, number>> = Object.freeze({ debug: 26 });

/** Types with no input port (the editor draws them 7 px narrower). */
const NO_INPUT = new Set(['comment', 'inject', 'catch', 'status', 'complete', 'link in', 'plcwire-heartbeat', 'http in', 'tab', 'group']);

/** What the editor writes on a node without a name (the common core types; others show their type). */
export function nodeLabel(n: FlowNode): string {
  if (n.name) return n.name;
  switch (n.type) {
    case 'debug':
      return `msg.${String(n.complete ?? 'payload')}`;
    case 'inject':
      return String(n.topic || n.payload || 'timestamp');
    case 'status':
    case 'catch':
    case 'complete':
      return `${n.type}: all`;
    default:
      return n.type;
  }
}

function outputsOf(n: FlowNode): number {
  if (typeof n.outputs === 'number') return n.outputs;
  return Array.isArray(n.wires) ? n.wires.length : 0;
}

/**
 * The node's box (w x h), how far its status reaches below it (0 for nodes
 * without one) and how far a button reaches past its left or right edge.
 */
export function estimatedSize(n: FlowNode): { w: number; h: number; below: number; left: number; right: number } {
  const h = Math.max(NODE_HEIGHT, outputsOf(n) * 15);
  const below = SHOWS_STATUS.has(n.type) || (n.type === 'debug' && n.tostatus === true) ? STATUS_BELOW : 0;
  const buttons = { left: BUTTON_LEFT[n.type] ?? 0, right: BUTTON_RIGHT[n.type] ?? 0 };
  if (n.l === false) return { w: NODE_HEIGHT, h, below, ...buttons };
  const text = nodeLabel(n).length * LABEL_PX_PER_CHAR + 50 + (NO_INPUT.has(n.type) ? 0 : 7);
  return { w: Math.max(MIN_NODE_WIDTH, 20 * Math.ceil(text / 20)), h, below, ...buttons };
}

/**
 * Where the editor puts a node of a flow:
 * - 'centred' on x, y: a deployed flows file (the demo), and an import that
 *   brings its own tab (the Dashboard 2 example);
 * - 'dropped': an import of nodes without a tab (the other examples) is
 *   dropped as a selection: every node first gets the default width, then
 *   grows to its label's width to the right, so its left edge sits at x - 50
 *   (editor-client view.js, importNodes and redraw) and a wide node reaches
 *   further right than its x suggests.
 */
export type Placement = 'centred' | 'dropped';

/** How the editor places `flow` (see Placement). */
export function placementOf(flow: FlowNode[], deployed: boolean): Placement {
  return deployed || flow.some((n) => n.type === 'tab') ? 'centred' : 'dropped';
}

/** The editor's default node width (its `node_width`). */
const DEFAULT_NODE_WIDTH = 100;

/** Nodes the editor draws on a tab (not config nodes, tabs or groups), with their estimated boxes (status and buttons included). */
export function drawnBoxes(flow: FlowNode[], placement: Placement): Map<string, Box[]> {
  const byTab = new Map<string, Box[]>();
  for (const n of flow) {
    if (typeof n.x !== 'number' || typeof n.y !== 'number' || n.type === 'group' || n.type === 'tab') continue;
    const { w, h, below, left: buttonLeft, right: buttonRight } = estimatedSize(n);
    const tab = n.z ?? '';
    const boxes = byTab.get(tab) ?? [];
    const left = placement === 'centred' ? n.x - w / 2 : n.x - DEFAULT_NODE_WIDTH / 2;
    boxes.push({
      id: n.id,
      label: nodeLabel(n),
      left: left - buttonLeft,
      right: left + w + buttonRight,
      top: n.y - h / 2,
      bottom: n.y + h / 2 + below,
    });
    byTab.set(tab, boxes);
  }
  return byTab;
}

/** Whether two boxes come closer than `gap` px on both axes (touching counts as overlapping for gap > 0). */
export function overlap(a: Box, b: Box, gap = 0): boolean {
  return a.left < b.right + gap && b.left < a.right + gap && a.top < b.bottom + gap && b.top < a.bottom + gap;
}

/**
 * Every pair of boxes on one tab that overlap, and with `canvas` every box
 * that reaches off the canvas (x or y below 0: a deployed flow keeps its
 * positions, while an imported one is placed where the user puts it).
 */
export function layoutProblems(boxesByTab: Map<string, Box[]>, options: { gap?: number; canvas?: boolean } = {}): string[] {
  const gap = options.gap ?? 0;
  const problems: string[] = [];
  const name = (b: Box) => `"${b.label}" (${b.id})`;
  for (const boxes of boxesByTab.values()) {
    for (let i = 0; i < boxes.length; i++) {
      const a = boxes[i]!;
      if (options.canvas && (a.left < 0 || a.top < 0)) problems.push(`${name(a)} reaches off the canvas (left ${a.left}, top ${a.top})`);
      for (let j = i + 1; j < boxes.length; j++) {
        const b = boxes[j]!;
        if (overlap(a, b, gap)) problems.push(`${name(a)} and ${name(b)} overlap`);
      }
    }
  }
  return problems;
}

/** Dashboard 2.0: the columns of a page at its widest breakpoint (12 without breakpoints). */
export function pageColumns(page: FlowNode): number {
  const points = Array.isArray(page.breakpoints) ? (page.breakpoints as { cols?: unknown }[]) : [];
  const cols = points.map((p) => Number(p.cols)).filter((c) => Number.isFinite(c) && c > 0);
  return cols.length > 0 ? Math.max(...cols) : 12;
}

/**
 * Dashboard 2.0 sizes: every widget in a group that exists and no wider than
 * it (width 0 fills the group), every group on a page that exists and no
 * wider than the page's columns.
 */
export function dashboardProblems(flow: FlowNode[]): string[] {
  const problems: string[] = [];
  const byId = new Map(flow.map((n) => [n.id, n]));
  for (const n of flow) {
    if (n.type === 'ui-group') {
      const page = byId.get(String(n.page));
      const width = Number(n.width);
      if (!page || page.type !== 'ui-page') problems.push(`group "${n.name}" is on no page`);
      else if (!(width >= 1 && width <= pageColumns(page)))
        problems.push(`group "${n.name}" is ${n.width} wide on a page of ${pageColumns(page)} columns`);
    } else if (n.type.startsWith('ui-') && typeof n.group === 'string' && n.group !== '') {
      const group = byId.get(n.group);
      const width = Number(n.width) || 0;
      if (!group || group.type !== 'ui-group') problems.push(`widget "${n.name}" (${n.id}) is in no group`);
      else if (width > Number(group.width))
        problems.push(`widget "${n.name}" (${n.id}) is ${width} wide in group "${group.name}" of ${group.width}`);
    }
  }
  return problems;
}
