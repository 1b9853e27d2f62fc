// Monaco's providers call `stvm lsp` through the bridge (POST /lsp, one JSON-RPC message each).
// Positions: Monaco counts lines and columns from 1, LSP from 0; both count UTF-16 code units.
"use strict";

let nextId = 1;
async function rpc(method, params) {
  const response = await fetch("/lsp", {method: "POST", body: JSON.stringify({jsonrpc: "2.0", id: nextId++, method, params})});
  const message = await response.json();
  if (message.error) throw new Error(`${method}: ${message.error.message}`);
  return message.result;
}
function notify(method, params) {
  return fetch("/lsp", {method: "POST", body: JSON.stringify({jsonrpc: "2.0", method, params})});
}
const toLsp = (p) => ({line: p.lineNumber - 1, character: p.column - 1});
const toRange = (r) => ({startLineNumber: r.start.line + 1, startColumn: r.start.character + 1,
                         endLineNumber: r.end.line + 1, endColumn: r.end.character + 1});
const docParams = (model, position) => ({textDocument: {uri: model.uri.toString()}, position: toLsp(position)});
const LSP_KINDS = [null, "Text", "Method", "Function", "Constructor", "Field", "Variable", "Class", "Interface",
  "Module", "Property", "Unit", "Value", "Enum", "Keyword", "Snippet", "Color", "File", "Reference", "Folder",
  "EnumMember", "Constant", "Struct", "Event", "Operator", "TypeParameter"];

require.config({paths: {vs: "/monaco/vs"}});
require(["vs/editor/editor.main"], function () {
  const ST = "structured-text";
  monaco.languages.register({id: ST});
  // colours only: every answer below comes from the language server, not from this tokenizer
  monaco.languages.setMonarchTokensProvider(ST, {
    ignoreCase: true,
    keywords: ["PROGRAM", "END_PROGRAM", "FUNCTION_BLOCK", "END_FUNCTION_BLOCK", "FUNCTION", "END_FUNCTION",
      "VAR", "VAR_INPUT", "VAR_OUTPUT", "VAR_IN_OUT", "VAR_EXTERNAL", "VAR_GLOBAL", "END_VAR", "IF", "THEN",
      "ELSIF", "ELSE", "END_IF", "CASE", "OF", "END_CASE", "FOR", "TO", "BY", "DO", "END_FOR", "WHILE",
      "END_WHILE", "REPEAT", "UNTIL", "END_REPEAT", "RETURN", "AND", "OR", "XOR", "NOT", "MOD", "TRUE", "FALSE",
      "ARRAY", "STRUCT", "END_STRUCT", "TYPE", "END_TYPE"],
    tokenizer: {root: [
      [/\(\*/, "comment", "@comment"], [/\/\/.*$/, "comment"], [/'[^']*'/, "string"],
      [/[A-Za-z_]\w*#[\w.]+/, "number"], [/\d[\d_.]*/, "number"],
      [/[A-Za-z_]\w*/, {cases: {"@keywords": "keyword", "@default": "identifier"}}]],
      comment: [[/\*\)/, "comment", "@pop"], [/./, "comment"], [/$/, "comment"]]},
  });

  monaco.languages.registerHoverProvider(ST, {async provideHover(model, position) {
    const hover = await rpc("textDocument/hover", docParams(model, position));
    if (!hover) return null;
    const contents = Array.isArray(hover.contents) ? hover.contents : [hover.contents];
    return {contents: contents.map((c) => ({value: typeof c === "string" ? c : c.value})),
            range: hover.range && toRange(hover.range)};
  }});

  monaco.languages.registerCompletionItemProvider(ST, {triggerCharacters: ["."], async provideCompletionItems(model, position, context) {
    const params = {...docParams(model, position), context: {triggerKind: context.triggerKind + 1, triggerCharacter: context.triggerCharacter}};
    const answer = await rpc("textDocument/completion", params);
    const items = Array.isArray(answer) ? answer : (answer ? answer.items : []);
    const word = model.getWordUntilPosition(position);
    const range = {startLineNumber: position.lineNumber, endLineNumber: position.lineNumber, startColumn: word.startColumn, endColumn: word.endColumn};
    return {incomplete: !Array.isArray(answer) && !!(answer && answer.isIncomplete), suggestions: items.map((item) => ({
      label: item.label, detail: item.detail, sortText: item.sortText, filterText: item.filterText,
      kind: monaco.languages.CompletionItemKind[LSP_KINDS[item.kind]] ?? monaco.languages.CompletionItemKind.Text,
      documentation: item.documentation && (item.documentation.value !== undefined ? {value: item.documentation.value} : item.documentation),
      insertText: item.textEdit ? item.textEdit.newText : (item.insertText ?? item.label),
      insertTextRules: item.insertTextFormat === 2 ? monaco.languages.CompletionItemInsertTextRule.InsertAsSnippet : undefined,
      range: item.textEdit && item.textEdit.range ? toRange(item.textEdit.range) : range}))};
  }});

  monaco.languages.registerSignatureHelpProvider(ST, {signatureHelpTriggerCharacters: ["(", ","], async provideSignatureHelp(model, position) {
    const help = await rpc("textDocument/signatureHelp", docParams(model, position));
    if (!help || !help.signatures || !help.signatures.length) return null;
    return {value: {activeSignature: help.activeSignature ?? 0, activeParameter: help.activeParameter ?? 0,
      signatures: help.signatures.map((s) => ({label: s.label, documentation: s.documentation,
        parameters: (s.parameters || []).map((p) => ({label: p.label, documentation: p.documentation}))}))},
      dispose() {}};
  }});

  monaco.languages.registerDefinitionProvider(ST, {async provideDefinition(model, position) {
    const answer = await rpc("textDocument/definition", docParams(model, position));
    const locations = answer ? (Array.isArray(answer) ? answer : [answer]) : [];
    return locations.map((l) => ({uri: monaco.Uri.parse(l.uri ?? l.targetUri), range: toRange(l.range ?? l.targetSelectionRange)}));
  }});

  const hintsChanged = new monaco.Emitter();
  monaco.languages.registerInlayHintsProvider(ST, {onDidChangeInlayHints: hintsChanged.event, async provideInlayHints(model, range) {
    const hints = await rpc("textDocument/inlayHint", {textDocument: {uri: model.uri.toString()},
      range: {start: {line: range.startLineNumber - 1, character: 0}, end: {line: range.endLineNumber, character: 0}}});
    return {hints: (hints || []).map((h) => ({
      label: typeof h.label === "string" ? h.label : h.label.map((part) => part.value).join(""),
      position: {lineNumber: h.position.line + 1, column: h.position.character + 1},
      paddingLeft: h.paddingLeft ?? true, paddingRight: h.paddingRight, kind: h.kind})), dispose() {}};
  }});

  // what the server sends by itself: diagnostics as markers, inlay-hint refreshes
  async function poll() {
    try {
      for (const event of await (await fetch("/events")).json()) {
        if (event.method === "textDocument/publishDiagnostics") {
          const model = monaco.editor.getModel(monaco.Uri.parse(event.params.uri));
          if (model) monaco.editor.setModelMarkers(model, "stvm", event.params.diagnostics.map((d) => ({
            ...toRange(d.range), message: d.message, code: d.code,
            severity: [0, 8, 4, 2, 1][d.severity ?? 1]})));
        } else if (event.method === "workspace/inlayHint/refresh") {
          hintsChanged.fire();
        }
      }
    } finally { setTimeout(poll, 250); }
  }

  // the shooting script calls this: initialize, open the file, show it
  window.openFile = async function (uri, text, initializationOptions) {
    await rpc("initialize", {processId: null, rootUri: null, initializationOptions,
      capabilities: {workspace: {inlayHint: {refreshSupport: true}},
        textDocument: {hover: {contentFormat: ["markdown", "plaintext"]},
          completion: {completionItem: {snippetSupport: true}}, inlayHint: {}, signatureHelp: {}}}});
    await notify("initialized", {});
    const model = monaco.editor.createModel(text, ST, monaco.Uri.parse(uri));
    let version = 1;
    await notify("textDocument/didOpen", {textDocument: {uri, languageId: ST, version, text}});
    model.onDidChangeContent(() => notify("textDocument/didChange",
      {textDocument: {uri, version: ++version}, contentChanges: [{text: model.getValue()}]}));
    window.editor = monaco.editor.create(document.getElementById("editor"), {
      model, theme: "vs-dark", fontSize: 15, minimap: {enabled: false}, automaticLayout: true,
      inlayHints: {enabled: "on"}, hover: {delay: 100}, scrollBeyondLastLine: false,
      stickyScroll: {enabled: false}});
    poll();
    return true;
  };
  window.monacoReady = true;
});
