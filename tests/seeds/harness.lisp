;;;; Seed replays: the tutorial pages of ../shared/seeds/ read at test time, their Lisp code
;;;; blocks pasted into this fresh SBCL as a user would, and what each page shows checked.
;;;;
;;;; A seed script (tests/seeds/seed-NNN.lisp) names its page with DEFINE-SEED, then lists every
;;;; code block of the page in tutorial order with REPLAY-BLOCK (run it, check what the page
;;;; shows) or EQUIVALENT-BLOCK (a shell or catkin step: its cram-plans equivalent is checked).
;;;; The page text is never copied into the repository: where the page's diff table cut a line
;;;; short, the script keeps only the completion of that line, keyed by block and line.
;;;; FINISH-SEED prints `seed NNN: K/N blocks' and exits 0 only when K = N and every code block
;;;; of the page was addressed.

(defpackage :cram-plans-seeds
  (:use :cl)
  (:nicknames :seeds)
  (:export #:define-seed #:seed-file #:page-lines #:code-blocks #:block-text
           #:replay-block #:equivalent-block #:finish-seed
           #:replay-text #:run-forms #:result-values #:result-output #:result-forms
           #:shown-output #:expect #:expect-log #:expect-printed
           #:*seed* #:*checkout* #:nbsp-diff-side #:table-diff-side #:plain-lines
           #:split-nbsp-row #:lines-block))

(in-package :cram-plans-seeds)

(defvar *checkout*
  (merge-pathnames "../../" (make-pathname :name nil :type nil :defaults *load-truename*))
  "The root of the cram-plans checkout this harness belongs to.")

;;; ------------------------------------------------------------------------------------------
;;; Reading the pages

(defun seed-file (number)
  "The page ../shared/seeds/NUMBER_*.txt beside the checkout, or NIL when absent."
  (first (directory (merge-pathnames (format nil "../shared/seeds/~a_*.txt" number) *checkout*))))

(defun read-lines (path)
  (with-open-file (in path :external-format :utf-8)
    (loop for line = (read-line in nil) while line collect (string-right-trim '(#\Return) line))))

(defun trim (s) (string-trim '(#\Space #\Tab #\No-break_space) s))

(defun strip-suffix (s suffix)
  (let ((n (length suffix)))
    (if (and (>= (length s) n) (string= suffix s :start2 (- (length s) n))) (subseq s 0 (- (length s) n)) s)))

(defun table-diff-side (line side)
  "The text of one row of a DokuWiki diff table (`- | old | + | new |', `old | new | ||',
`+ | new | ||') on SIDE (:OLD or :NEW), or NIL when the row is a hunk header."
  (let ((l line))
    (cond ((and (>= (length l) 5) (string= "Line " l :end2 5) (search ": | Line " l)) nil)
          ((and (>= (length l) 4) (string= "- | " l :end2 4))
           (let* ((rest (subseq l 4))
                  (sep (search " | + | " rest)))
             (cond
               ;; `- | + ||': on the old side a removed blank line, not a line `+'
               ((and (eq side :old) (>= (length rest) 3) (string= "+ |" rest :end2 3))
                "")
               (t
             (if sep
                 (if (eq side :old) (subseq rest 0 sep)
                     (strip-suffix (strip-suffix (subseq rest (+ sep 7)) " |") "|"))
                 (if (eq side :old) (strip-suffix (strip-suffix rest " | ||") " |") ""))))))
          ((and (>= (length l) 4) (string= "+ | " l :end2 4))
           (if (eq side :new) (strip-suffix (strip-suffix (subseq l 4) " | ||") " |") ""))
          (t
           ;; an unchanged row: the same text twice, `X | X | ||'
           (let* ((body (strip-suffix l " | ||"))
                  (n (length body)))
             (if (and (evenp (- n 3)) (> n 3))
                 (let ((half (/ (- n 3) 2)))
                   (if (and (string= (subseq body 0 half) (subseq body (+ half 3)))
                            (string= " | " (subseq body half (+ half 3))))
                       (subseq body 0 half)
                       body))
                 (if (string= body "|") "" body)))))))

(defun split-nbsp-row (line)
  "One row of a side-by-side diff whose cells are separated by no-break spaces: returns the
marker character (#\\- #\\+ or #\\Space) and the cells."
  (let ((cells '()) (start 0))
    (loop for pos = (position #\No-break_space line :start start)
          do (push (subseq line start pos) cells)
             (if pos (setf start (1+ pos)) (return)))
    (nreverse cells)))

(defun fold-blanks (s)
  "S with no-break spaces as spaces, runs of blanks as one space, trimmed."
  (let ((out (make-string-output-stream)) (blank nil))
    (loop for c across (trim s)
          do (if (member c '(#\Space #\Tab #\No-break_space))
                 (setf blank t)
                 (progn (when blank (write-char #\Space out)) (setf blank nil) (write-char c out))))
    (get-output-stream-string out)))

(defun common-ends (a b)
  "The length of the common prefix plus that of the common suffix of A and B."
  (let* ((p (or (mismatch a b) (length a)))
         (s (let ((m (mismatch a b :from-end t)))
              (if m (- (length a) m) (length a)))))
    (+ p (min s (- (min (length a) (length b)) p)))))

(defun split-changed-row (body)
  "BODY is a changed row without its leading `-': `old+new', where the `+' that separates
the sides may follow a no-break space or the old text directly. Of the `+' characters, the
one whose sides read most alike (common prefix and suffix) separates them; ties go to the
first. Returns OLD and NEW (NEW is NIL when the row has no `+')."
  (let ((best nil) (best-score -1))
    (loop for i = (position #\+ body) then (position #\+ body :start (1+ i))
          while i
          do (let ((score (common-ends (fold-blanks (subseq body 0 i))
                                       (fold-blanks (subseq body (1+ i))))))
               (when (> score best-score) (setf best i best-score score))))
    (if best
        (values (subseq body 0 best) (subseq body (1+ best)))
        (values body nil))))

(defun nbsp-diff-side (line side)
  "The text of one row of a side-by-side diff on SIDE (:OLD or :NEW). Rows: `-old+new' (a
changed row; the `+' may follow a no-break space or the old text directly), `-old' (deleted),
`<nbsp>+new' (added), `<nbsp>text<nbsp>text' (unchanged: the same text twice). A row that
begins a hunk carries one extra leading space."
  (let* ((l (if (and (plusp (length line)) (char= (char line 0) #\Space)) (subseq line 1) line))
         (n (length l)))
    (flet ((clean (s) (string-right-trim '(#\No-break_space #\Space) s)))
      (cond ((and (plusp n) (char= (char l 0) #\-))
             (multiple-value-bind (old new) (split-changed-row (subseq l 1))
               (if (eq side :old) (clean old) (if new (clean new) ""))))
            ((and (>= n 2) (char= (char l 0) #\No-break_space) (char= (char l 1) #\+))
             (if (eq side :new) (clean (subseq l 2)) ""))
            (t ;; unchanged: the same text twice
             (let* ((s (if (and (plusp n) (char= (char l 0) #\No-break_space)) (subseq l 1) l))
                    (n (length s)))
               (loop for k from (floor n 2) downto 1
                     when (and (<= (* 2 k) n)
                               (string= (trim (subseq s 0 k)) (trim (subseq s k))))
                       do (return (subseq s 0 k))
                     finally (return s))))))))

(defun plain-lines (line side)
  "A plain page: every line is the text itself."
  (declare (ignore side))
  line)

(defstruct seed
  number path format side lines blocks
  (replayed 0) (passed 0) (addressed '()) (failures '()))

(defvar *seed* nil "The seed being replayed.")

(defun page-lines (path format side)
  "The lines of PATH on SIDE of its diff FORMAT (:TABLE, :NBSP or :PLAIN), as (LINE-NUMBER . TEXT)."
  (let ((fn (ecase format (:table #'table-diff-side) (:nbsp #'nbsp-diff-side) (:plain #'plain-lines))))
    (loop for line in (read-lines path)
          for n from 1
          for text = (funcall fn line side)
          when text collect (cons n (substitute #\Space #\No-break_space text)))))

(defun code-start-p (text) (search "<code lisp>" text))
(defun code-end-p (text)
  (let ((s (trim text)))
    (or (search "</code>" s) (and (>= (length s) 2) (string= "</" s :end2 2)))))

(defun code-blocks (lines)
  "The `<code lisp>' blocks of LINES: a list of lists of (LINE-NUMBER . TEXT), in page order.
A block written on one line (`<code lisp> (form) </code>') is one line."
  (let ((blocks '()) (current nil) (in nil))
    (dolist (entry lines)
      (let* ((text (cdr entry)) (start (code-start-p text)))
        (cond ((and (not in) start)
               (let ((after (subseq text (+ start (length "<code lisp>")))))
                 (cond ((search "</" after)
                        (push (list (cons (car entry) (subseq after 0 (search "</" after)))) blocks))
                       (t (setf in t current (if (string= (trim after) "") '()
                                                 (list (cons (car entry) after))))))))
              ((and in (code-end-p text))
               (let ((before (subseq text 0 (or (search "</" text) 0))))
                 (unless (string= (trim before) "") (push (cons (car entry) before) current)))
               (push (nreverse current) blocks)
               (setf in nil current nil))
              (in (push entry current)))))
    (when in (push (nreverse current) blocks))
    (nreverse blocks)))

(defun lines-block (lines from to)
  "The entries of LINES (see PAGE-LINES) from page line FROM to page line TO inclusive: a code
block for pages whose blocks have no `<code lisp>' markers, or whose diff shows a block in pieces."
  (remove-if-not (lambda (e) (<= from (car e) to)) lines))

(defmacro define-seed (number &key (format :table) (side :new) blocks)
  "Open the page NUMBER of ../shared/seeds/ in FORMAT (:TABLE or :NBSP diff tables, :PLAIN text)
and take SIDE (:NEW, or :OLD where the newest revision has no code). BLOCKS, when given, is a
form returning the list of code blocks (each a list of (LINE-NUMBER . TEXT)) for pages without
`<code lisp>' markers; it may use the variable LINES."
  `(let* ((path (seed-file ,number)))
     (unless path
       (format t "~&seed ~a: skipped (../shared/seeds/~a_*.txt is not beside the checkout)~%"
               ,number ,number)
       (finish-output)
       (uiop:quit 0))
     (let ((lines (page-lines path ,format ,side)))
       (declare (ignorable lines))
       (setf *seed* (make-seed :number ,number :path path :format ,format :side ,side :lines lines
                               :blocks ,(or blocks '(code-blocks lines)))))
     (format t "~&;; seed ~a: ~a, ~d code blocks on the ~(~a~) side~%" ,number
             (file-namestring (seed-path *seed*)) (length (seed-blocks *seed*)) ,side)))

;;; ------------------------------------------------------------------------------------------
;;; Completions

(defun block-text (index &key completions anchor)
  "The text of code block INDEX (1-based) of the current page, with COMPLETIONS applied: a
list of (LINE CUT FULL) where LINE is the 1-based line within the block, CUT the text the page
shows there (trimmed; the line is checked to still read so) and FULL the whole line, or
several lines where the page's diff skipped some (a hunk gap). ANCHOR, when
given, must occur in the block's first non-empty line (so a changed page is noticed)."
  (let* ((blocks (seed-blocks *seed*)))
    (unless (<= 1 index (length blocks))
      (error "seed ~a has ~d code blocks, no block ~d" (seed-number *seed*) (length blocks) index))
    (let ((lines (mapcar #'cdr (nth (1- index) blocks))))
      (when anchor
        (let ((first (find-if (lambda (l) (string/= (trim l) "")) lines)))
          (unless (and first (search anchor first))
            (error "block ~d of seed ~a begins ~s, not with ~s: has the page changed?"
                   index (seed-number *seed*) first anchor))))
      (dolist (c completions)
        (destructuring-bind (line cut full) c
          (unless (<= 1 line (length lines))
            (error "completion of line ~d: block ~d has ~d lines" line index (length lines)))
          (unless (string= (trim (nth (1- line) lines)) (trim cut))
            (error "completion of block ~d line ~d expects the page to show ~s there, it shows ~s"
                   index line cut (nth (1- line) lines)))
          (setf (nth (1- line) lines) full)))
      (format nil "~{~a~^~%~}" lines))))

;;; ------------------------------------------------------------------------------------------
;;; Pasting text into the REPL

(defstruct result
  "What replaying a block gave: the forms read as input, the values of the last one, what
was printed, and the page's shown output per input form."
  forms values output shown)

(defun prompt-at (text pos)
  "When a REPL prompt `NAME> ' starts at POS (at the start of a line), its package name and end."
  (let ((end (position-if-not (lambda (c) (or (alphanumericp c) (find c "-_.:"))) text :start pos)))
    (when (and end (> end pos) (< end (length text)) (char= (char text end) #\>)
               (or (= pos 0) (char= (char text (1- pos)) #\Newline)))
      (values (subseq text pos end) (1+ end)))))

(defun input-form-p (form)
  "A form a user types: a call, a special form or a quoted/backquoted expression of one."
  (and (consp form) (or (symbolp (car form)) (and (consp (car form)) (eq (caar form) 'lambda)))))

;;; One REPL step at a time, as a user pastes: read a form in the package of the latest prompt
;;; (or of the latest IN-PACKAGE), evaluate it, and read on; text that is not an input form is
;;; the output the page shows for the form before it.

(defun skip-blank (text pos)
  (or (position-if-not (lambda (c) (member c '(#\Space #\Tab #\Newline))) text :start pos) (length text)))

(defun next-prompt-position (text pos)
  (loop for p = (position #\Newline text :start pos) then (position #\Newline text :start (1+ p))
        while p
        when (prompt-at text (1+ p)) return (1+ p)
        finally (return (length text))))

(defun short (x)
  (let ((s (handler-case (let ((*print-length* 6) (*print-level* 3)) (prin1-to-string x))
             (error () "#<unprintable>"))))
    (if (> (length s) 160) (concatenate 'string (subseq s 0 157) "...") s)))

(defun comments-only-p (text pos)
  "Whether TEXT from POS on holds nothing but blank lines and `;' comments."
  (loop for line in (uiop:split-string (subseq text pos) :separator '(#\Newline))
        for s = (trim line)
        always (or (string= s "") (char= (char s 0) #\;))))

(defun call-with-log-stream (stream thunk)
  "Call THUNK with CPL:*LOG-STREAM* (when cram-plans is loaded) bound to STREAM, so the log
lines a form writes are part of what it printed."
  (let ((log (find-symbol "*LOG-STREAM*" "CRAM-LANGUAGE")))
    (if log
        (progv (list log) (list stream) (funcall thunk))
        (funcall thunk))))

(defmacro with-log-stream ((stream) &body body)
  "Run BODY with the CRAM log lines going to STREAM as well (see CALL-WITH-LOG-STREAM)."
  `(call-with-log-stream ,stream (lambda () ,@body)))

(defun replay-text (text &key (package "CL-USER") (evaluate t))
  "Paste TEXT into this image's REPL: every input form is read in the package of the latest
prompt and evaluated in turn (unless EVALUATE is NIL). Returns a RESULT. A form that signals
aborts the replay with that condition, as it would abort the user's paste."
  (let ((*package* (or (find-package package) (find-package "CL-USER")))
        (pos 0) (n (length text)) (forms '()) (shown '()) (values '())
        (out (make-string-output-stream))
        ;; a symbol typed right after a prompt (`DEMO> btr:*current-bullet-world*') is input too
        (after-prompt nil))
    (let ((echo (make-broadcast-stream *standard-output* out)))
      (loop
        (setf pos (skip-blank text pos))
        (when (>= pos n) (return))
        (multiple-value-bind (name after) (prompt-at text pos)
          (cond (name
                 (let ((p (find-package (string-upcase name))))
                   (if p (setf *package* p)
                       (error "the page's prompt ~a> names no package of this image" name)))
                 (setf pos after after-prompt t))
                (t
                 (let ((form nil) (end nil))
                   (handler-case (multiple-value-setq (form end) (read-from-string text t nil :start pos))
                     (reader-error () (setf end nil))
                     (end-of-file ()
                       ;; only comments left (e.g. `; Evaluation aborted on ...'): shown output
                       (if (and shown (comments-only-p text pos))
                           (setf end nil)
                           (error "an unfinished form at ~s" (subseq text pos (min n (+ pos 60)))))))
                   (cond ((and end (or (input-form-p form)
                                       (and after-prompt form (symbolp form)
                                            (not (keywordp form)))))
                          (push form forms) (push "" shown)
                          (setf pos end after-prompt nil)
                          (when evaluate
                            (let ((*standard-output* echo) (*trace-output* echo))
                              ;; CRAM-shaped log lines go to CPL:*LOG-STREAM*: keep them too
                              (with-log-stream (echo)
                                (setf values (multiple-value-list (eval form)))))
                            ;; as the REPL does: * ** *** hold the latest values
                            (setf *** ** ** * * (first values))
                            (format t "~&;; => ~{~s~^, ~}~%" (mapcar #'short values))))
                         (t
                          (let ((next (next-prompt-position text pos)))
                            (if shown
                                (setf (first shown) (concatenate 'string (first shown) (subseq text pos next)))
                                (error "the block starts with text that is not a form: ~s"
                                       (subseq text pos (min n (+ pos 60)))))
                            (setf pos next))))))))))
    (make-result :forms (nreverse forms) :values values
                 :output (get-output-stream-string out) :shown (nreverse shown))))

(defun shown-output (result &optional (index nil))
  "The output the page shows after input form INDEX (default: the last) of RESULT, trimmed."
  (trim (nth (or index (1- (length (result-shown result)))) (result-shown result))))

;;; ------------------------------------------------------------------------------------------
;;; Checks and counting

(define-condition check-failed (error)
  ((what :initarg :what :reader what))
  (:report (lambda (c s) (format s "~a" (what c)))))

(defun expect (ok format &rest args)
  "Fail the current block unless OK, with a message made from FORMAT and ARGS."
  (unless ok (error 'check-failed :what (apply #'format nil format args)))
  t)

(defun expect-log (result &rest needles)
  "Every string of NEEDLES occurs, in this order, in what the block printed."
  (let ((start 0) (text (result-output result)))
    (dolist (needle needles t)
      (let ((pos (search needle text :start2 start)))
        (expect pos "the log lacks ~s (after position ~d)" needle start)
        (setf start (+ pos (length needle)))))))

(defun expect-printed (value shown)
  "VALUE prints (with PRINC, case and whitespace folded) as the page's SHOWN text begins."
  (flet ((fold (s) (string-upcase (format nil "~{~a~^ ~}"
                                          (uiop:split-string (trim s) :separator '(#\Space #\Newline #\Tab))))))
    (let ((p (fold (princ-to-string value))) (s (fold shown)))
      (expect (and (plusp (length s)) (string= s p :end2 (min (length p) (length s))))
              "printed ~s, the page shows ~s" (short p) (short s)))))

(defun note-addressed (index)
  (when (member index (seed-addressed *seed*))
    (error "block ~d of seed ~a is addressed twice" index (seed-number *seed*)))
  (push index (seed-addressed *seed*)))

(defun run-step (label thunk)
  (incf (seed-replayed *seed*))
  (format t "~&;; --- seed ~a ~a~%" (seed-number *seed*) label)
  (finish-output)
  (let ((ok (block try
              (handler-bind ((serious-condition
                               (lambda (c)
                                 (format t "~&;; FAILED seed ~a ~a: ~a~%" (seed-number *seed*) label
                                         (handler-case (princ-to-string c) (error () (type-of c))))
                                 ;; SEED_BACKTRACE=1 in the environment: where it failed, too
                                 (when (uiop:getenv "SEED_BACKTRACE")
                                   (sb-debug:print-backtrace :count 40))
                                 (push (cons label c) (seed-failures *seed*))
                                 (return-from try nil))))
                (funcall thunk)
                t))))
    (when ok (incf (seed-passed *seed*)))
    (format t "~&;; ~:[FAIL~;ok~]   seed ~a ~a~%" ok (seed-number *seed*) label)
    (finish-output)
    ok))

(defmacro replay-block (index (&key name completions anchor (package "CL-USER") (evaluate t))
                        &body checks)
  "Replay code block INDEX of the page (with COMPLETIONS, see BLOCK-TEXT) at the REPL, then run
CHECKS with RESULT bound to its RESULT. The block counts as passed only when every form ran and
every check held."
  `(progn
     (note-addressed ,index)
     (run-step (format nil "block ~d~@[ (~a)~]" ,index ,name)
               (lambda ()
                 (let* ((text (block-text ,index :completions ,completions :anchor ,anchor))
                        (result (replay-text text :package ,package :evaluate ,evaluate)))
                   (declare (ignorable result))
                   ,@checks)))))

(defmacro equivalent-block (index (&key name anchor reason) &body checks)
  "Code block INDEX is a shell, catkin or editor step the user does outside Lisp: REASON says so,
and CHECKS verify its cram-plans equivalent (with TEXT bound to the block's text)."
  `(progn
     (note-addressed ,index)
     (run-step (format nil "block ~d~@[ (~a)~] [equivalent: ~a]" ,index ,name ,reason)
               (lambda ()
                 (let ((text (block-text ,index :anchor ,anchor)))
                   (declare (ignorable text))
                   ,@checks)))))

(defun finish-seed ()
  "Print `seed NNN: K/N blocks' (N counts every code block of the page) and exit 0 only when
every block ran and matched what the page shows."
  (let* ((s *seed*) (total (length (seed-blocks s)))
         (missing (loop for i from 1 to total unless (member i (seed-addressed s)) collect i)))
    (when missing
      (format t "~&;; seed ~a: blocks never replayed nor addressed: ~{~d~^, ~}~%" (seed-number s) missing))
    (dolist (f (reverse (seed-failures s)))
      (format t "~&;; seed ~a failed ~a: ~a~%" (seed-number s) (car f)
              (handler-case (princ-to-string (cdr f)) (error () (type-of (cdr f))))))
    (format t "~&seed ~a: ~d/~d blocks~%" (seed-number s) (seed-passed s) total)
    (finish-output)
    (uiop:quit (if (and (null missing) (= (seed-passed s) total) (= (seed-replayed s) total)) 0 1))))
