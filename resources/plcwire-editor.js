/**
 * Editor code the plcwire dialogs share (connection, read, write, heartbeat,
 * control): deploy-time validation with the runtime's parser, the tag table,
 * address hints. Node-RED serves it at
 * resources/@plcwire/node-red-siemens/plcwire-editor.js; each node's .html
 * loads it with a <script src>, and the editor runs a node's inline scripts
 * only once it has loaded. Loaded by several dialogs, it runs once: a second
 * run would forget the parser's answers the first one collected.
 */
(function () {
  'use strict';
  if (window.plcwireEditor) return;
  var editor = (window.plcwireEditor = {});

  /** The connection config node chosen in a dialog, or null when none (or "add new…"). */
  editor.connectionNode = function (connectionId) {
    return connectionId && connectionId !== '_ADD_' ? RED.nodes.node(connectionId) : null;
  };

  /** The URL of a connection config node chosen in a dialog, or '' when none. */
  editor.urlOf = function (connectionId) {
    var c = editor.connectionNode(connectionId);
    return c ? c.url || '' : '';
  };

  // --- tags by name: the symbol sources of a connection node, compiled by the runtime ---

  /** The sources of connection `connectionId` as the runtime's endpoints take them, or undefined when it has none. */
  editor.symbolsOf = function (connectionId) {
    var c = editor.connectionNode(connectionId);
    if (c && Array.isArray(c.symbolSources) && c.symbolSources.length > 0)
      return { symbolSources: c.symbolSources, dbNumbers: c.dbNumbers || [] };
    // No sources, but the PLC's own table from Browse PLC (s7plus://): the tag tables complete from it as from compiled sources.
    if (c && browsed[c.id]) return { symbolSources: [], dbNumbers: [], browsed: c.id };
    return undefined;
  };

  var browsed = {}; // connection id → the runtime's answer of plcwire/s7plus/browse, with byName

  /** Keeps what Browse PLC answered for connection `connectionId` (the shape of a compile: blocks, entries, types, errors). */
  editor.setBrowsed = function (connectionId, answer) {
    var table = { blocks: answer.blocks || [], entries: answer.entries || [], types: answer.types || [], errors: [], byName: {} };
    table.entries.forEach(function (e) {
      table.byName[e.name] = e;
    });
    browsed[connectionId] = table;
  };

  /** A short fingerprint of a set of sources (32-bit FNV-1a over their JSON), to cache the runtime's answers by; '' for none. */
  function keyOf(symbols) {
    if (!symbols) return '';
    if (symbols.browsed) return 'browse:' + symbols.browsed;
    var text = JSON.stringify([symbols.symbolSources, symbols.dbNumbers]);
    var h = 0x811c9dc5;
    for (var i = 0; i < text.length; i++) {
      h ^= text.charCodeAt(i);
      h = Math.imul(h, 0x01000193) >>> 0;
    }
    return text.length + ':' + h.toString(16);
  }

  var compiled = {}; // keyOf(symbols) → the runtime's answer, with byName
  var compiling = {}; // keyOf(symbols) → callbacks waiting for it

  /**
   * The runtime's compile of `symbols` ({ symbolSources, dbNumbers }):
   * callback({ blocks, entries, types, errors, byName }), once per set of
   * sources (answers are kept). Without sources: an empty table.
   */
  editor.compileSymbols = function (symbols, callback) {
    var key = keyOf(symbols);
    if (!key) return callback({ blocks: [], entries: [], types: [], errors: [], byName: {} });
    if (symbols.browsed) return callback(browsed[symbols.browsed] || { blocks: [], entries: [], types: [], errors: [], byName: {} });
    if (compiled[key]) return callback(compiled[key]);
    if (compiling[key]) return void compiling[key].push(callback);
    compiling[key] = [callback];
    $.ajax({
      url: 'plcwire/symbols',
      type: 'POST',
      contentType: 'application/json',
      data: JSON.stringify(symbols),
      success: function (res) {
        var answer = res || { blocks: [], entries: [], types: [], errors: [] };
        answer.byName = {};
        (answer.entries || []).forEach(function (e) {
          answer.byName[e.name] = e;
        });
        compiled[key] = answer;
        finish(answer);
      },
      error: function (xhr) {
        // Not kept: the next question asks again.
        finish({ blocks: [], entries: [], types: [], byName: {}, errors: [{ message: String((xhr && xhr.statusText) || 'error') }] });
      },
    });
    function finish(answer) {
      var waiting = compiling[key] || [];
      delete compiling[key];
      waiting.forEach(function (cb) {
        cb(answer);
      });
    }
  };

  /** Names without their quotes, in lower case: what a typed prefix is compared with. */
  function plainName(name) {
    return String(name).replace(/"/g, '').toLowerCase();
  }

  /** Completions for `typed` among the entries of a compiled table: names starting with it first, then containing it; at most `max`. */
  editor.completions = function (answer, typed, max) {
    var want = plainName(typed).trim();
    if (!want) return [];
    var starts = [];
    var contains = [];
    (answer.entries || []).forEach(function (e) {
      var plain = plainName(e.name);
      var at = plain.indexOf(want);
      if (at === 0) starts.push(e);
      else if (at > 0) contains.push(e);
    });
    return starts.concat(contains).slice(0, max || 50);
  };

  /**
   * The rows "all members" adds for a struct (or array) entry: one per
   * elementary member and per array of elementary values, found through
   * nested structs and arrays of structs; each named by its path from the
   * struct's own name (`Motor.Speed` for `"Tank".Motor`, `Level` for `"Tank"`).
   */
  editor.memberRows = function (answer, name) {
    var top = answer.byName[name];
    if (!top) return [];
    var lastDot = top.name.lastIndexOf('.');
    var cut = lastDot > top.name.lastIndexOf('"') ? lastDot + 1 : top.name.length + 1;
    var rows = [];
    function walk(e) {
      (e.children || []).forEach(function (childName) {
        var child = answer.byName[childName];
        if (!child) return;
        var first = child.children && answer.byName[child.children[0]];
        var whole = child.kind === 'elementary' || (child.kind === 'array' && (!first || first.kind === 'elementary'));
        if (whole) rows.push({ name: child.name.slice(cut), address: child.name });
        else walk(child);
      });
    }
    walk(top);
    return rows;
  };

  /** Asks the runtime about addresses (the library's own parser, and the connection's symbols if given): callback(results) with { address: { ok, type, message } }. */
  editor.validate = function (url, addresses, callback, symbols) {
    $.ajax({
      url: 'plcwire/validate',
      type: 'POST',
      contentType: 'application/json',
      data: JSON.stringify($.extend({ url: url || undefined, addresses: addresses }, symbols || {})),
      success: function (res) {
        callback((res && res.results) || {}, res && res.url);
      },
      error: function () {
        callback({});
      },
    });
  };

  // --- deploy-time validation: the nodes' validate functions, with the library's parser ---
  // A validate function must answer at once, the parser runs in the runtime: the functions answer from
  // what the runtime said before, ask about what it has not been asked yet, and every plcwire node is
  // validated again when the answers arrive (so the red triangle appears a moment after a flow loads).

  // Questions are asked per URL and set of symbol sources (a name means what the connection's sources say).
  var answers = {}; // question key → { '': the URL's answer, '\u0001': the sources' answer, address: the address's answer }
  var wanted = {}; // question key → { url, symbols, addresses: { address: true } }, for the next question
  var asking;

  /** The question a connection's addresses are asked in: its URL and symbol sources. */
  function questionOf(url, symbols) {
    return { key: url + '\u0000' + keyOf(symbols), url: url, symbols: symbols };
  }

  function answerOf(question, address) {
    var known = answers[question.key] && answers[question.key][address];
    if (known) return known;
    var w = (wanted[question.key] = wanted[question.key] || { url: question.url, symbols: question.symbols, addresses: {} });
    w.addresses[address] = true;
    if (!asking) asking = setTimeout(ask, 0); // one question per URL and sources for everything validated in this turn
    return undefined;
  }

  function ask() {
    asking = undefined;
    var batch = wanted;
    wanted = {};
    Object.keys(batch).forEach(function (key) {
      var question = batch[key];
      var url = question.url;
      var addresses = Object.keys(question.addresses).filter(function (a) {
        return a && a !== '\u0001';
      });
      $.ajax({
        url: 'plcwire/validate',
        type: 'POST',
        contentType: 'application/json',
        data: JSON.stringify($.extend({ url: url || undefined, addresses: addresses }, question.symbols || {})),
        success: function (res) {
          var known = (answers[key] = answers[key] || {});
          known[''] = (res && res.url) || { ok: true };
          known['\u0001'] = (res && res.symbols) || { ok: true };
          // With an invalid URL there are no address answers: the connection is what is wrong.
          addresses.forEach(function (a) {
            known[a] = (res && res.results && res.results[a]) || { ok: true };
          });
          revalidate();
        },
        // No answer (runtime gone): nothing is cached, the next validation asks again.
      });
    });
  }

  /** Validates every plcwire node again (config nodes first: their users' validity depends on them). */
  function revalidate() {
    var redraw = false;
    var configs = false;
    function again(n) {
      var before = n.valid + JSON.stringify(n.validationErrors || []);
      RED.editor.validateNode(n);
      if (before === n.valid + JSON.stringify(n.validationErrors || [])) return false;
      n.dirty = true;
      redraw = true;
      return true;
    }
    RED.nodes.eachConfig(function (n) {
      if (n.type === 'plcwire-connection' && again(n)) configs = true;
    });
    RED.nodes.eachNode(function (n) {
      if (n.type.indexOf('plcwire-') === 0) again(n);
    });
    if (configs && RED.sidebar.config && RED.sidebar.config.refresh) RED.sidebar.config.refresh();
    if (redraw) RED.view.redraw(true);
  }

  /** The parser's objection to a URL, or undefined (also while the answer is on its way). */
  editor.urlProblem = function (url) {
    var answer = answerOf(questionOf(String(url == null ? '' : url).trim()), '');
    return answer && !answer.ok ? answer.message : undefined;
  };

  /** A compile error as the dialogs show it: file, line and column when the library knows them. */
  editor.sourceErrorText = function (e, t) {
    return e.file
      ? t('plcwire-connection.editor.errorAt', { file: e.file, line: e.line, column: e.column, message: e.message })
      : e.message;
  };

  /** For a connection's `symbolSources` validate: the compile errors of its sources (the first few), or undefined. */
  editor.sourcesProblem = function (node) {
    var url = String(node.url == null ? '' : node.url).trim();
    var symbols =
      Array.isArray(node.symbolSources) && node.symbolSources.length
        ? { symbolSources: node.symbolSources, dbNumbers: node.dbNumbers || [] }
        : undefined;
    if (!symbols) return undefined;
    var question = questionOf(url, symbols);
    var urlAnswer = answerOf(question, '');
    var answer = answerOf(question, '\u0001');
    if (!urlAnswer || !urlAnswer.ok || !answer || answer.ok) return undefined;
    return (answer.errors || []).slice(0, 3).map(function (e) {
      return e.message;
    });
  };

  /** The parser's objections to addresses (names among them) with the URL and symbol sources of connection `connectionId`. */
  function addressProblems(connectionId, addresses) {
    var question = questionOf(editor.urlOf(connectionId), editor.symbolsOf(connectionId));
    var urlAnswer = answerOf(question, '');
    var out = [];
    addresses.forEach(function (a) {
      var answer = a ? answerOf(question, a) : undefined;
      if (urlAnswer && urlAnswer.ok && answer && !answer.ok) out.push(answer.message);
    });
    return out;
  }

  /**
   * The names given to more than one of `rows` ({ name, address }), as the
   * runtime counts them (POST plcwire/duplicates): calls back with
   * [{ name, rows: indexes }], or [] when the runtime does not answer.
   */
  editor.duplicateNames = function (rows, callback) {
    $.ajax({
      url: 'plcwire/duplicates',
      type: 'POST',
      contentType: 'application/json',
      data: JSON.stringify({ tags: tagRows(rows) }),
      success: function (res) {
        callback((res && res.duplicates) || []);
      },
      error: function () {
        callback([]);
      },
    });
  };

  function tagRows(rows) {
    return (rows || []).map(function (r) {
      return { name: String((r && r.name) || ''), address: String((r && r.address) || '') };
    });
  }

  // A validate function answers at once: the names used twice in a node's table as the runtime said
  // before, asked when not known yet (every plcwire node is validated again when the answer arrives).
  var duplicateAnswers = {}; // the table's rows as JSON → [{ name, rows }]
  function knownDuplicates(rows) {
    var key = JSON.stringify(tagRows(rows));
    if (duplicateAnswers[key]) return duplicateAnswers[key];
    if (duplicateAnswers[key] === undefined) {
      if (Object.keys(duplicateAnswers).length > 200) duplicateAnswers = {}; // tables edited away are asked again if they come back
      duplicateAnswers[key] = null; // asked; null until the answer
      editor.duplicateNames(rows, function (duplicates) {
        duplicateAnswers[key] = duplicates;
        if (duplicates.length) revalidate();
      });
    }
    return [];
  }

  /** For a node's `tags` validate: true, or what is wrong (names used twice, addresses the parser refuses). */
  editor.validateTags = function (node, tags) {
    if (!Array.isArray(tags)) return false;
    var problems = knownDuplicates(tags).map(function (d) {
      return node._('plcwire.editor.duplicateName', { name: d.name });
    });
    problems = problems.concat(
      addressProblems(
        node.connection,
        tags.map(function (t) {
          return String((t && t.address) || '').trim();
        }),
      ),
    );
    return problems.length ? problems : true;
  };

  /** For a node's single-address validate (heartbeat): true, or the parser's objection. An empty address is valid. */
  editor.validateAddress = function (node, address) {
    var problems = addressProblems(node.connection, [String(address == null ? '' : address).trim()]);
    return problems.length ? problems[0] : true;
  };

  /**
   * One address input: validates it as it is typed and shows the type or the
   * problem in `hint`. Returns { check, dispose }; dispose (on Done and Cancel)
   * stops a pending validation, which would otherwise outlive the dialog.
   */
  editor.watchAddress = function (input, hint, urlOf, symbolsOf) {
    var timer;
    var closed = false;
    function check() {
      if (closed) return;
      var address = String(input.val() || '').trim();
      input.removeClass('plcwire-invalid');
      hint.text('').removeClass('plcwire-bad');
      if (!address) return;
      editor.validate(
        urlOf(),
        [address],
        function (results) {
          var r = results[address];
          if (closed || !r) return;
          // A name: its type and the absolute address it stands for (none in an optimized block: read by name).
          if (r.ok) hint.text(r.type + (r.count > 1 ? '[' + r.count + ']' : '') + (r.symbol && r.address ? ' = ' + r.address : ''));
          else {
            input.addClass('plcwire-invalid');
            hint.text(r.message).addClass('plcwire-bad');
          }
        },
        symbolsOf ? symbolsOf() : undefined,
      );
    }
    input.on('input change', function () {
      clearTimeout(timer);
      timer = setTimeout(check, 300);
    });
    check();
    return {
      check: check,
      dispose: function () {
        closed = true;
        clearTimeout(timer);
      },
    };
  };

  /** Asks the runtime to read CSV text into tags (the library's importer, with the connection's parser). */
  function importCsv(url, text, callback) {
    $.ajax({
      url: 'plcwire/csv',
      type: 'POST',
      contentType: 'application/json',
      data: JSON.stringify({ url: url || undefined, text: text }),
      success: function (res) {
        callback((res && res.tags) || [], (res && res.problems) || []);
      },
      error: function (xhr) {
        RED.notify(String((xhr && xhr.statusText) || 'error'), 'error');
      },
    });
  }

  /** Asks the runtime for the table as CSV (the library's tagsToCsv, the form the importer reads back). */
  function exportCsv(tags, callback) {
    $.ajax({
      url: 'plcwire/csv/export',
      type: 'POST',
      contentType: 'application/json',
      data: JSON.stringify({ tags: tags }),
      success: function (res) {
        callback(String((res && res.csv) || ''));
      },
      error: function (xhr) {
        RED.notify(String((xhr && xhr.statusText) || 'error'), 'error');
      },
    });
  }

  /**
   * The tag table of the read and write dialogs: an editableList of name/address
   * rows with add/remove, validation against the chosen connection (addresses
   * by the runtime's parser, names used twice), CSV import (replace or append)
   * and export. With symbol sources on the connection (`symbolsOf()`: what
   * editor.symbolsOf gives), an address cell completes names from the
   * compiled table, each row shows the absolute address a name resolves to
   * beside its type, and a struct's row offers "all members".
   * Returns { value(): [{ name, address }], revalidate(), dispose() };
   * dispose on Done and Cancel, so no validation runs after the dialog closed.
   */
  editor.tagTable = function (container, tags, urlOf, t, symbolsOf) {
    symbolsOf =
      symbolsOf ||
      function () {
        return undefined;
      };
    var toolbar = $('<div class="plcwire-tags-toolbar">').insertBefore(container);
    var importButton = $('<button type="button" class="red-ui-button red-ui-button-small"><i class="fa fa-upload"></i> </button>').appendTo(
      toolbar,
    );
    importButton.append(document.createTextNode(t('plcwire.editor.importCsv')));
    var exportButton = $(
      '<button type="button" class="red-ui-button red-ui-button-small"><i class="fa fa-download"></i> </button>',
    ).appendTo(toolbar);
    exportButton.append(document.createTextNode(t('plcwire.editor.exportCsv')));
    var file = $('<input type="file" accept=".csv,text/csv,text/plain" style="display:none">').appendTo(toolbar);
    var timer;
    var closed = false;

    function rowOf(item) {
      return {
        name: String(item.find('.plcwire-tag-name').val() || '').trim(),
        address: String(item.find('.plcwire-tag-address').val() || '').trim(),
      };
    }

    function markDuplicates(items) {
      editor.duplicateNames(items.map(rowOf), function (duplicates) {
        if (closed) return;
        var nameOf = {}; // row index → the name it shares with another row
        duplicates.forEach(function (d) {
          d.rows.forEach(function (i) {
            nameOf[i] = d.name;
          });
        });
        items.forEach(function (item, i) {
          var name = nameOf[i];
          item
            .find('.plcwire-tag-name')
            .toggleClass('plcwire-invalid', name !== undefined)
            .attr('title', name !== undefined ? t('plcwire.editor.duplicateName', { name: name }) : '');
        });
      });
    }

    function validateAll() {
      if (closed) return;
      var items = [];
      container.editableList('items').each(function () {
        items.push($(this));
      });
      markDuplicates(items);
      var addresses = items
        .map(function (r) {
          return rowOf(r).address;
        })
        .filter(Boolean);
      if (!addresses.length) return;
      editor.validate(
        urlOf(),
        addresses,
        function (results) {
          if (closed) return;
          items.forEach(function (r) {
            var input = r.find('.plcwire-tag-address');
            var type = r.find('.plcwire-tag-type');
            var resolved = r.find('.plcwire-tag-resolved');
            var members = r.find('.plcwire-tag-members');
            var res = results[String(input.val() || '').trim()];
            var problem = r.find('.plcwire-tag-problem');
            input.removeClass('plcwire-invalid');
            type.removeClass('plcwire-invalid-text').text('').attr('title', '');
            resolved.text('').attr('title', '');
            problem.text('').attr('title', '');
            members.hide().removeData('symbol');
            if (!res) return;
            if (res.ok) {
              type.text(res.type + (res.count > 1 ? '[' + res.count + ']' : '')).attr('title', res.type);
              // A name: the absolute address it stands for, as the library resolved it (none in an optimized block).
              if (res.symbol && res.address) resolved.text(res.address).attr('title', res.symbol + ' = ' + res.address);
              if (res.symbol && res.kind !== 'elementary') {
                members
                  .data('symbol', res.symbol)
                  .attr('title', t('plcwire.editor.addMembersTitle', { name: res.symbol }))
                  .show();
              }
            } else {
              input.addClass('plcwire-invalid');
              type.addClass('plcwire-invalid-text').text(t('plcwire.editor.invalid')).attr('title', res.message);
              // The reason in the row itself, not only on hover: the runtime's words without the address repeated.
              problem.text(editor.shortProblem(res.message, String(input.val() || '').trim())).attr('title', res.message);
            }
          });
        },
        symbolsOf(),
      );
    }

    /** Completion of names from the connection's compiled symbols (none without sources). */
    function complete(value, done) {
      var symbols = symbolsOf();
      if (!symbols || closed) return done([]);
      editor.compileSymbols(symbols, function (answer) {
        if (closed) return done([]);
        done(
          editor.completions(answer, value, 50).map(function (e) {
            // Names, types and addresses come from the sources: text nodes, never HTML.
            var label = $('<div class="plcwire-completion">');
            $('<span class="plcwire-completion-name">').text(e.name).appendTo(label);
            $('<span class="plcwire-completion-type">').text(e.type).appendTo(label);
            $('<span class="plcwire-completion-address">')
              .text(e.address || '')
              .appendTo(label);
            return { value: e.name, label: label };
          }),
        );
      });
    }

    /** "all members": a row for every member of the struct in row `item`, after the table's rows. */
    function addMembers(item) {
      var name = item.find('.plcwire-tag-members').data('symbol');
      var symbols = symbolsOf();
      if (!name || !symbols) return;
      editor.compileSymbols(symbols, function (answer) {
        if (closed) return;
        var rows = editor.memberRows(answer, name);
        rows.forEach(function (row) {
          container.editableList('addItem', row);
        });
        later();
        RED.notify(t('plcwire.editor.membersAdded', { count: rows.length, name: name }), { type: 'success', timeout: 3000 });
      });
    }
    function later() {
      if (closed) return;
      clearTimeout(timer);
      timer = setTimeout(validateAll, 300);
    }

    editor.tagTableStyle();
    // No `height: 'auto'`: with it the list never scrolls, and once oneditresize gives it a height its rows
    // are drawn past that height, over the "add" button. Without it the list scrolls within the height the
    // dialog leaves it (resizeTagTable), as Node-RED's own lists (switch, change) do.
    container.css({ 'min-height': '150px', 'min-width': '450px' }).editableList({
      addButton: t('plcwire.editor.addTag'),
      removable: true,
      sortable: true,
      addItem: function (row, index, data) {
        var line = $('<div class="plcwire-tag-row">').appendTo(row);
        $('<input type="text" class="plcwire-tag-name">')
          .attr('placeholder', t('plcwire.editor.tagName'))
          .val(data.name || '')
          .appendTo(line)
          .on('input change', later);
        var address = $('<input type="text" class="plcwire-tag-address">')
          .attr('placeholder', t('plcwire.editor.tagAddress'))
          .val(data.address || '')
          .appendTo(line)
          .on('input change', later);
        // Node-RED's completion widget (the one its msg and env fields use); it asks complete() as the user types.
        if ($.fn.autoComplete) address.autoComplete({ search: complete, minLength: 1 });
        // The type, the absolute address a name stands for, or why the address is refused: a line of its own
        // under the inputs, as wide as the row, so a long name's address is read in full.
        var info = $('<div class="plcwire-tag-info">').appendTo(line);
        $('<span class="plcwire-tag-type">').appendTo(info);
        $('<span class="plcwire-tag-resolved">').appendTo(info);
        $('<span class="plcwire-tag-problem">').appendTo(info);
        var members = $(
          '<button type="button" class="red-ui-button red-ui-button-small plcwire-tag-members"><i class="fa fa-sitemap"></i> </button>',
        )
          .hide()
          .insertBefore(info)
          .on('click', function () {
            addMembers(row);
          });
        members.append(document.createTextNode(t('plcwire.editor.addMembers')));
        later();
      },
      removeItem: later,
    });
    container.closest('.red-ui-editableList').addClass('plcwire-tag-table');
    (tags || []).forEach(function (tag) {
      container.editableList('addItem', tag);
    });

    function addImported(imported, problems, replace) {
      if (closed) return;
      if (replace) container.editableList('empty');
      imported.forEach(function (tag) {
        container.editableList('addItem', tag);
      });
      later();
      RED.notify(t('plcwire.editor.imported', { count: imported.length }), { type: 'success', timeout: 3000 });
      if (problems.length) {
        // Names and addresses come from the file: text nodes, never HTML.
        var list = $('<div>').append($('<p>').text(t('plcwire.editor.importProblems')));
        var ul = $('<ul>').appendTo(list);
        problems.slice(0, 10).forEach(function (p) {
          $('<li>')
            .text(t('plcwire.editor.line', { line: p.line, message: p.message }))
            .appendTo(ul);
        });
        if (problems.length > 10) $('<li>').text('…').appendTo(ul);
        RED.notify(list, { type: 'warning', timeout: 10000 });
      }
    }

    /** Into an empty table at once; into one with rows, as the user chooses: replace them or append. */
    function chooseAndAdd(imported, problems) {
      if (closed) return;
      if (api.value().length === 0 || imported.length === 0) return addImported(imported, problems, false);
      var choice = RED.notify(t('plcwire.editor.importChoice', { count: imported.length }), {
        modal: true,
        fixed: true,
        type: 'compact',
        buttons: [
          {
            id: 'plcwire-import-cancel',
            text: RED._('common.label.cancel'),
            click: function () {
              choice.close();
            },
          },
          {
            id: 'plcwire-import-append',
            text: t('plcwire.editor.append'),
            click: function () {
              choice.close();
              addImported(imported, problems, false);
            },
          },
          {
            id: 'plcwire-import-replace',
            text: t('plcwire.editor.replace'),
            class: 'primary',
            click: function () {
              choice.close();
              addImported(imported, problems, true);
            },
          },
        ],
      });
    }

    importButton.on('click', function () {
      file.val('');
      file.trigger('click');
    });
    file.on('change', function () {
      var f = this.files && this.files[0];
      if (!f) return;
      var reader = new FileReader();
      reader.onload = function () {
        if (!closed) importCsv(urlOf(), String(reader.result || ''), chooseAndAdd);
      };
      reader.readAsText(f);
    });
    exportButton.on('click', function () {
      exportCsv(api.value(), function (csv) {
        var blob = new Blob([csv], { type: 'text/csv' });
        var a = document.createElement('a');
        a.href = URL.createObjectURL(blob);
        a.download = 'plcwire-tags.csv';
        document.body.appendChild(a);
        a.click();
        setTimeout(function () {
          URL.revokeObjectURL(a.href);
          a.remove();
        }, 0);
      });
    });

    var api = {
      value: function () {
        var out = [];
        container.editableList('items').each(function () {
          var row = rowOf($(this));
          if (row.address) out.push(row);
        });
        return out;
      },
      revalidate: validateAll,
      dispose: function () {
        closed = true;
        clearTimeout(timer);
        container.find('.plcwire-tag-address').each(function () {
          if ($(this).hasClass('red-ui-autoComplete')) $(this).autoComplete('destroy');
        });
      },
    };
    return api;
  };

  /**
   * The tag table of a read or write dialog, wired to its connection field:
   * rows revalidate when the connection changes. Returns the table.
   */
  editor.dialogTagTable = function (node) {
    var t = function (k, o) {
      return node._(k, o);
    };
    var urlOf = function () {
      return editor.urlOf($('#node-input-connection').val());
    };
    var symbolsOf = function () {
      return editor.symbolsOf($('#node-input-connection').val());
    };
    var table = editor.tagTable($('#node-input-plcwire-tags'), node.tags, urlOf, t, symbolsOf);
    $('#node-input-connection').on('change', function () {
      table.revalidate();
    });
    return table;
  };

  /**
   * Gives the tag table the dialog height the other rows leave (oneditresize):
   * the dialog's height less every other row of the form and what the tags
   * row holds besides the list (its label, the CSV toolbar). The list keeps
   * at least 150 px (on a very low window the dialog scrolls instead).
   */
  editor.resizeTagTable = function (size) {
    var list = $('#node-input-plcwire-tags');
    var row = list.closest('.form-row');
    if (!row.length) return;
    var height = size.height;
    row.siblings(':visible').each(function () {
      height -= $(this).outerHeight(true);
    });
    var whole = list.closest('.red-ui-editableList');
    height -= row.outerHeight(true) - whole.outerHeight(true);
    list.editableList('height', Math.max(150, Math.floor(height)));
  };

  /**
   * The runtime's objection to an address as a row shows it: without the
   * "invalid address "…":" prefix that repeats what the row's input shows.
   */
  editor.shortProblem = function (message, address) {
    var text = String(message == null ? '' : message);
    var prefix = 'invalid address "' + address + '": ';
    return text.indexOf(prefix) === 0 ? text.slice(prefix.length) : text;
  };

  /** The tag table's layout, added to the page once (shared by the read and write dialogs). */
  editor.tagTableStyle = function () {
    if (document.getElementById('plcwire-tag-table-style')) return;
    var css = [
      '.plcwire-tag-table .plcwire-tag-row { display: flex; flex-wrap: wrap; align-items: center; gap: 2px 6px; }',
      '.plcwire-tag-table .plcwire-tag-row input.plcwire-tag-name { flex: 2 1 0; min-width: 60px; margin: 0; }',
      '.plcwire-tag-table .plcwire-tag-row input.plcwire-tag-address { flex: 3 1 0; min-width: 120px; margin: 0; font-family: monospace; }',
      '.plcwire-tag-table .plcwire-tag-row .plcwire-tag-members { flex: 0 0 auto; }',
      '.plcwire-tag-table .plcwire-tag-info { flex: 1 0 100%; min-width: 0; display: flex; flex-wrap: wrap; gap: 0 8px; font-size: 0.85em;',
      '  line-height: 1.4em; color: var(--red-ui-secondary-text-color); }',
      '.plcwire-tag-table .plcwire-tag-info:has(span:not(:empty)) { min-height: 1.4em; }',
      '.plcwire-tag-table .plcwire-tag-info .plcwire-tag-type { flex: 0 0 auto; overflow: visible; white-space: nowrap; }',
      '.plcwire-tag-table .plcwire-tag-info .plcwire-tag-resolved { flex: 0 1 auto; font-family: monospace; white-space: nowrap; overflow: visible; }',
      ".plcwire-tag-table .plcwire-tag-info .plcwire-tag-resolved:not(:empty)::before { content: '\\2192  '; font-family: sans-serif; }",
      '.plcwire-tag-table .plcwire-tag-info .plcwire-tag-problem { flex: 1 1 0; min-width: 0; white-space: normal; overflow-wrap: anywhere; color: var(--red-ui-text-color-error); }',
      '.plcwire-tag-table .plcwire-tag-info .plcwire-tag-problem:empty { display: none; }',
    ].join('\n');
    $('<style id="plcwire-tag-table-style">').text(css).appendTo(document.head);
  };
})();
